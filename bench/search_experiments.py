"""Issue 51's experiments, remade with one command:
`python bench/search_experiments.py [--seeds 1 2 3] [--budget N] [--duration S]`.

* **trade-off**: speed against cost of transport on 4x4x4 (paper-voxel) and on one task
  (task-slope), NSGA-II and AFPO (their new default variation, 'explore') against the
  weighted-sum GA (three weights) and random search, every run stopped by `max_simulations`
  at the same budget; the normalised hypervolume of each row's front so far
  (`pareto.normalised_hypervolume`, both objectives scaled by the ideal and nadir points of all
  the methods' final fronts of that task and seed) against simulations.
* **window**: steady-state with W = P, 2P, 4P against the paper's GA on 4x4x4 (speed alone):
  simulations and wall time until the best speed so far reaches the GA's final best.

Runs go through the library (`softevo.library.start`, the service's generation step without its
store), on `--workers` local processes. Writes `docs/experiments/search/results.json`, and the
figures `hypervolume.png`, `window.png`; prints the tables.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from softevo import library
from softevo.core.config import resolve
from softevo.core.evolution import Evolution
from softevo.core.search import pareto

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "experiments" / "search"
COT_REFERENCE = 2000.0
OBJECTIVES: list[Any] = [
    "speed",
    {"measure": "cost_of_transport", "goal": "min", "reference": COT_REFERENCE},
]
SPEED_SCALE, COT_SCALE = 0.1, 1000.0  # the weighted GA's scales (EXPERIMENTS.md, issue 36)
WEIGHTS = (0.25, 0.5, 0.75)
TASKS = ("paper-voxel", "task-slope")


def methods() -> dict[str, dict[str, Any]]:
    """Each method's settings over the task's preset."""
    found: dict[str, dict[str, Any]] = {"NSGA-II": {"algorithm": "nsga2"}}
    found["AFPO"] = {"algorithm": "afpo"}
    for w in WEIGHTS:
        found[f"GA w={w:g}"] = {"options": {"weights": [w / SPEED_SCALE, (1 - w) / COT_SCALE]}}
    found["random"] = {"algorithm": "random"}
    # the variation's effect: NSGA-II with the paper's operators, as runs stored before issue 51
    found["NSGA-II paper"] = {"algorithm": "nsga2", "options": {"variation": "paper"}}
    return found


def trade_off(preset: str, method: dict[str, Any], seed: int, args: argparse.Namespace) -> dict:
    """One run to the budget: each row's simulations so far and front so far."""
    config = {
        "preset": preset,
        "shape": [4, 4, 4],
        "seed": seed,
        "objectives": OBJECTIVES,
        "generations": 10_000,
        "max_simulations": args.budget,
        "sim": {"duration": args.duration},
        **method,
    }
    run = library.start(config, workers=args.workers)
    rows: list[dict[str, Any]] = []
    started = time.perf_counter()
    simulations = 0
    for row in run:
        simulations += row["evaluations"]
        front = run.evolution.state.data["front"]
        rows.append(
            {
                "simulations": simulations,
                "front": front,
                "diversity": row["diversity"],
                "hypervolume": row["hypervolume"],
                "best": row["best_so_far"],
            }
        )
    run.close()
    return {"rows": rows, "seconds": time.perf_counter() - started, "config": run.config.to_json()}


def window_run(window: int | None, seed: int, args: argparse.Namespace, rq: str | None) -> dict:
    """Steady-state (W births in flight) or, with None, the paper's GA, on the local pool or
    (`rq`, a Redis URL) on the RQ workers serving it: best so far against simulations and wall
    time."""
    request: dict[str, Any] = {
        "preset": "paper-voxel",
        "shape": [4, 4, 4],
        "seed": seed,
        "generations": 10_000,
        "max_simulations": args.window_budget,
        "sim": {"duration": args.duration},
    }
    if window is not None:
        request = {**request, "algorithm": "steady-state", "options": {"window": window}}
    evolution = Evolution.start(resolve(request, new=True))
    if rq is None:
        from softevo.core.physics.evaluation import make_evaluator

        evaluator = make_evaluator(args.workers)
    else:
        from softevo.worker.evaluator import RQEvaluator

        evaluator = RQEvaluator(rq)
    rows, started = [], time.perf_counter()
    try:
        while not evolution.done:
            row = evolution.step(evaluator)
            rows.append(
                {
                    "simulations": evolution.evaluations,
                    "best": row.best_so_far,
                    "seconds": time.perf_counter() - started,
                }
            )
    finally:
        evaluator.close()
    return {"rows": rows}


def normalised(rows: list[dict], ideal: np.ndarray, nadir: np.ndarray) -> list[float]:
    return [
        pareto.normalised_hypervolume(np.asarray(row["front"], dtype=float), ideal, nadir)
        for row in rows
    ]


def bounds(runs: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """The ideal point (the best of every objective on any final front) and the nadir (the
    worst of every objective on any final front) of these runs, maximised: every method's
    front lies in the box, so each counts from its own ends."""
    points = np.concatenate([np.asarray(run["rows"][-1]["front"], dtype=float) for run in runs])
    return points.max(axis=0), points.min(axis=0)


def run_trade_off(args: argparse.Namespace, results: dict[str, Any]) -> None:
    """Every method on every task and seed (those already in `results` kept), each scored in
    the box of all of that task's and seed's final fronts."""
    for preset in args.tasks:
        for seed in args.seeds:
            kept = results.setdefault("trade_off", {}).setdefault(preset, {})
            runs = kept.get(str(seed), {}).get("runs", {})
            for name, method in methods().items():
                if name not in runs:
                    runs[name] = trade_off(preset, method, seed, args)
                    runs[name].pop("config")
                    print(f"{preset} seed {seed} {name}: {runs[name]['seconds']:.0f} s", flush=True)
            ideal, nadir = bounds(list(runs.values()))
            for run in runs.values():
                run["normalised"] = normalised(run["rows"], ideal, nadir)
            kept[str(seed)] = {"ideal": ideal.tolist(), "nadir": nadir.tolist(), "runs": runs}


def run_windows(args: argparse.Namespace, results: dict[str, Any]) -> None:
    """GA and W = P, 2P, 4P on every seed, on the local pool and (with --rq) on RQ workers."""
    population = 25
    backends = [("local", None)] + ([("rq", args.rq)] if args.rq else [])
    for seed in args.seeds:
        for where, rq in backends:
            found = {"GA": window_run(None, seed, args, rq)}
            for k in (1, 2, 4):
                found[f"W={k}P"] = window_run(k * population, seed, args, rq)
            results.setdefault("window", {}).setdefault(where, {})[str(seed)] = found
            (args.out / "results.json").write_text(json.dumps(results))  # kept seed by seed
            print(f"window {where} seed {seed} done", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument("--budget", type=int, default=300, help="simulations per run")
    parser.add_argument("--duration", type=float, default=4.0, help="simulated seconds")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--tasks", nargs="+", choices=TASKS, default=list(TASKS))
    parser.add_argument("--window-budget", type=int, default=600, help="simulations, window")
    parser.add_argument(
        "--rq",
        metavar="URL",
        help="also run the window part on the RQ workers of this Redis "
        "(start them first: softevo worker --url URL, twice)",
    )
    parser.add_argument("--part", choices=("trade-off", "window", "all"), default="all")
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "results.json"
    results: dict[str, Any] = json.loads(path.read_text()) if path.exists() else {}
    settings = {
        "budget": args.budget,
        "window_budget": args.window_budget,
        "duration": args.duration,
        "workers": args.workers,
        "seeds": args.seeds,
    }
    results.setdefault("settings", {})[args.part] = settings
    if args.part in ("trade-off", "all"):
        run_trade_off(args, results)
        path.write_text(json.dumps(results))
    if args.part in ("window", "all"):
        run_windows(args, results)
        path.write_text(json.dumps(results))
    from search_report import report

    report(results, args.out)


if __name__ == "__main__":
    main()
