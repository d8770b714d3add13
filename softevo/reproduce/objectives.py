"""`softevo reproduce --objectives`: several objectives and age protection, through the API
(issue 36). Two experiments at paper-voxel settings (25 robots a generation), seeds 1-3:

* **trade-off** (4x4x4): speed against cost of transport. The weighted-sum GA (`ga` with
  `options.weights`, three weightings) sets the budget: B = the mean simulations of its three
  runs on that seed. NSGA-II and random search get generations enough to pass B, and every run
  of the experiment is read at its last generation within B simulations: the hypervolume from
  its curve, the front from its individuals up to that generation.
* **age** (4x4x3, 4x4x4, 3x3x6): AFPO against the paper's GA on speed alone. AFPO gets that
  seed's GA simulations: P at generation 0, then P - S new robots a generation (S survivors).

The tables and figures are `objectives_report`'s.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass, field
from typing import Any

from softevo.client import Client
from softevo.core.search import pareto
from softevo.core.search.front import front_rows, front_values
from softevo.core.search.survivors import n_survivors
from softevo.core.search.vectors import parse_objectives, reference_point
from softevo.reproduce.client import wait_runs

#: Speed against cost of transport, with the hypervolume reference point every run of the
#: trade-off shares: speed 0 m/s, cost of transport 2000 (about the 85th percentile of random
#: 4x4x4 robots': a front is scored on the robots that trade, not on the worst ones).
COT_REFERENCE = 2000.0
OBJECTIVES: list[Any] = [
    "speed",
    {"measure": "cost_of_transport", "goal": "min", "reference": COT_REFERENCE},
]
#: The weighted GA's scales: w on speed / SPEED_SCALE, 1 - w on cost of transport / COT_SCALE
#: (typical values of an evolved 4x4x4 robot), so a weight says how much each counts.
SPEED_SCALE, COT_SCALE = 0.1, 1000.0
SPEED_WEIGHTS = (0.25, 0.5, 0.75)
#: NSGA-II's generations assume only this fraction of P new robots a generation, so that it
#: passes the budget: once its survivors converge most of its children repeat a genome and come
#: from the cache (measured at 50 generations: 3.7 new robots a generation on seed 1).
NSGA2_NEW = 0.1
#: The paper's collapse: diversity below this (EXPERIMENTS.md, the nine boxes).
COLLAPSE = 0.25

FULL: dict[str, Any] = {
    "front_shape": [4, 4, 4],
    "shapes": [[4, 4, 3], [4, 4, 4], [3, 3, 6]],
    "seeds": [1, 2, 3],
    "settings": {},  # paper-voxel as it is: 100 generations
}
QUICK: dict[str, Any] = {
    "front_shape": [2, 2, 2],
    "shapes": [[2, 2, 2]],
    "seeds": [1],
    "settings": {"population": 6, "generations": 3, "sim": {"duration": 1.0, "settle_time": 0.3}},
}


def weighted_name(weight: float) -> str:
    return f"GA w={weight:g}"


TRADE_METHODS = ("NSGA-II", *map(weighted_name, SPEED_WEIGHTS), "random search")
AGE_METHODS = ("GA", "AFPO")


@dataclass
class Results:
    """What the two experiments measured: finished runs by key, their curves, the trade-off's
    budget per seed and each trade-off run's front (maximised values) at that budget."""

    plan: dict[str, Any]
    runs: dict[tuple, dict[str, Any]] = field(default_factory=dict)
    curves: dict[tuple, list[dict[str, Any]]] = field(default_factory=dict)
    budgets: dict[int, float] = field(default_factory=dict)
    fronts: dict[tuple, list[dict[str, Any]]] = field(default_factory=dict)
    cuts: dict[tuple, int] = field(default_factory=dict)  # key -> generation read


def weights(speed_weight: float) -> list[float]:
    """The weighted GA's `options.weights` for speed and cost of transport (maximised: the
    cost enters negated, so both weights are positive)."""
    return [speed_weight / SPEED_SCALE, (1 - speed_weight) / COT_SCALE]


def run_objectives(client: Client, quick: bool) -> Results:
    """Both experiments, finished and read."""
    plan = QUICK if quick else FULL
    results = Results(plan)
    base = {"preset": "paper-voxel", **plan["settings"]}
    trade = {**base, "shape": plan["front_shape"], "objectives": OBJECTIVES}
    first: dict[tuple, int] = {}
    for seed in plan["seeds"]:
        for w in SPEED_WEIGHTS:
            first[("trade", weighted_name(w), seed)] = client.run(
                **trade, seed=seed, options={"weights": weights(w)}
            ).id
    for shape in plan["shapes"]:
        for seed in plan["seeds"]:
            first[("age", _box(shape), "GA", seed)] = client.run(**base, shape=shape, seed=seed).id
    _wait(client, results, first)
    _wait(client, results, _second_round(client, results, base, trade))
    for key, run in results.runs.items():
        results.curves[key] = client.get_run(run["id"]).curve()
    for key in results.runs:
        if key[0] == "trade":
            _read_at_budget(client, results, key)
    return results


def _wait(client: Client, results: Results, submitted: dict[tuple, int]) -> None:
    finished = wait_runs(client, list(submitted.values()), "objectives")
    results.runs.update(zip(submitted, finished, strict=True))


def _second_round(
    client: Client, results: Results, base: dict[str, Any], trade: dict[str, Any]
) -> dict[tuple, int]:
    """NSGA-II and random search on each seed's budget, AFPO on each GA run's simulations."""
    plan, population = results.plan, _population(results)
    submitted: dict[tuple, int] = {}
    for seed in plan["seeds"]:
        budget = statistics.fmean(
            results.runs[("trade", weighted_name(w), seed)]["progress"]["evaluations"]
            for w in SPEED_WEIGHTS
        )
        results.budgets[seed] = budget
        new = max(1.0, NSGA2_NEW * population)
        submitted[("trade", "NSGA-II", seed)] = client.run(
            **{
                **trade,
                "seed": seed,
                "algorithm": "nsga2",
                "generations": 1 + math.ceil(max(0.0, budget - population) / new),
            }
        ).id
        submitted[("trade", "random search", seed)] = client.run(
            **{
                **trade,
                "seed": seed,
                "algorithm": "random",
                "generations": math.ceil(budget / population),
            }
        ).id
    children = population - n_survivors(population, 0.5, newcomers=1)  # mutants and a newcomer
    for shape in plan["shapes"]:
        for seed in plan["seeds"]:
            ga = results.runs[("age", _box(shape), "GA", seed)]
            generations = 1 + round(max(0, ga["progress"]["evaluations"] - population) / children)
            submitted[("age", _box(shape), "AFPO", seed)] = client.run(
                **{
                    **base,
                    "shape": shape,
                    "seed": seed,
                    "algorithm": "afpo",
                    "generations": max(1, generations),
                }
            ).id
    return submitted


def _population(results: Results) -> int:
    return int(next(iter(results.runs.values()))["config"]["population"])


def _box(shape: list[int]) -> str:
    return "x".join(map(str, shape))


def _read_at_budget(client: Client, results: Results, key: tuple) -> None:
    """The generation of `key`'s run last within its seed's budget, and its front there."""
    budget = results.budgets[key[2]]
    total, cut = 0, 0
    for row in results.curves[key]:
        total += row["evaluations"]
        if total > budget and row["generation"] > 0:
            break
        cut = row["generation"]
    results.cuts[key] = cut
    run = results.runs[key]
    specs = parse_objectives(run["config"]["objectives"])
    rows = [i for i in client.get_run(run["id"]).individuals() if i["generation"] <= cut]
    results.fronts[key] = front_rows(specs, rows)


def simulations_at(curve: list[dict[str, Any]], generation: int) -> int:
    """Simulations of a run up to and including `generation`."""
    return sum(row["evaluations"] for row in curve if row["generation"] <= generation)


def trade_rows(results: Results) -> list[dict[str, Any]]:
    """One row per method: hypervolume at the budget by seed, mean and std, and the front."""
    rows = []
    specs = parse_objectives(OBJECTIVES)
    default = reference_point(parse_objectives(["speed", "-cost_of_transport"]))
    for method in TRADE_METHODS:
        keys = [("trade", method, seed) for seed in results.plan["seeds"]]
        at = [results.curves[k][results.cuts[k]] for k in keys]
        volumes = [row["hypervolume"] for row in at]
        wide = [pareto.hypervolume(front_values(specs, results.fronts[k]), default) for k in keys]
        rows.append(
            {
                "method": method,
                "hypervolume_by_seed": " ".join(f"{v:.3f}" for v in volumes),
                "hypervolume_mean": statistics.fmean(volumes),
                "hypervolume_std": statistics.pstdev(volumes),
                "hypervolume_default_mean": statistics.fmean(wide),
                "front_size_mean": statistics.fmean(row["front_size"] for row in at),
                "best_speed_mean": statistics.fmean(row["best_so_far"] for row in at),
                "lowest_cot_mean": statistics.fmean(
                    min(p["measures"]["cost_of_transport"] for p in results.fronts[k]) for k in keys
                ),
                "simulations_mean": statistics.fmean(
                    simulations_at(results.curves[k], results.cuts[k]) for k in keys
                ),
                "generations_read": " ".join(str(results.cuts[k] + 1) for k in keys),
            }
        )
    return rows


def age_rows(results: Results) -> list[dict[str, Any]]:
    """One row per box and method: best speed, simulations, and when diversity collapsed."""
    rows = []
    for shape in results.plan["shapes"]:
        for method in AGE_METHODS:
            keys = [("age", _box(shape), method, s) for s in results.plan["seeds"]]
            curves = [results.curves[k] for k in keys]
            best = [curve[-1]["best_so_far"] for curve in curves]
            below = ["-" if b is None else str(b) for b in map(_first_below, curves)]
            rows.append(
                {
                    "box": _box(shape),
                    "method": method,
                    "best_by_seed": " ".join(f"{b:.4f}" for b in best),
                    "best_mean": statistics.fmean(best),
                    "best_std": statistics.pstdev(best),
                    "simulations_mean": statistics.fmean(
                        simulations_at(c, c[-1]["generation"]) for c in curves
                    ),
                    "generations": curves[0][-1]["generation"] + 1,
                    "collapse_generation_by_seed": " ".join(below),
                    "final_diversity_mean": statistics.fmean(c[-1]["diversity"] for c in curves),
                    "min_diversity_mean": statistics.fmean(
                        min(r["diversity"] for r in c) for c in curves
                    ),
                }
            )
    return rows


def _first_below(curve: list[dict[str, Any]]) -> int | None:
    """The first generation whose diversity is below COLLAPSE, or None."""
    return next((row["generation"] for row in curve if row["diversity"] < COLLAPSE), None)
