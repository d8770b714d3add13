"""The experiments as groups of runs: submitted through the API (reused with `--resume`),
waited for, and read back (curves, budgets, rows)."""

from __future__ import annotations

import json
import math
import statistics
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

from softevo.client import Client
from softevo.core.config import resolve
from softevo.core.status import RunStatus
from softevo.reproduce.plan import CLOCK, FINAL, GA_ON_FOCUS, REFERENCES, Plan

# -- the experiments -------------------------------------------------------------------------------


@dataclass
class Group:
    """The runs of one experiment, variant and box (one per seed)."""

    experiment: str
    variant: str
    shape: tuple[int, int, int]
    run_ids: list[int] = field(default_factory=list)
    runs: list[dict[str, Any]] = field(default_factory=list)

    def row(self) -> dict[str, Any]:
        best = [
            r["progress"]["best_fitness"] for r in self.runs if r["status"] == RunStatus.COMPLETED
        ]
        best = [b for b in best if b is not None]
        walls = [wall_seconds(r) for r in self.runs]
        return {
            "experiment": self.experiment,
            "variant": self.variant,
            "shape": "x".join(map(str, self.shape)),
            "seeds": " ".join(str(r["seed"]) for r in self.runs),
            "completed": sum(r["status"] == RunStatus.COMPLETED for r in self.runs),
            "best_mean": statistics.fmean(best) if best else None,
            "best_std": statistics.pstdev(best) if best else None,
            "best_min": min(best) if best else None,
            "best_max": max(best) if best else None,
            "best_by_seed": " ".join(
                f"{r['seed']}:{r['progress']['best_fitness']:.6g}"
                for r in self.runs
                if r["status"] == RunStatus.COMPLETED and r["progress"]["best_fitness"] is not None
            ),
            "evaluations_mean": statistics.fmean(r["progress"]["evaluations"] for r in self.runs),
            "generations": self.runs[0]["progress"]["generations"] if self.runs else None,
            "population": self.runs[0]["config"]["population"] if self.runs else None,
            "wall_seconds_mean": statistics.fmean(walls) if walls else None,
        }


def wall_seconds(run: dict[str, Any]) -> float:
    if not run.get("started_at") or not run.get("finished_at"):
        return math.nan
    started = datetime.fromisoformat(run["started_at"])
    return (datetime.fromisoformat(run["finished_at"]) - started).total_seconds()


def _key(config: dict[str, Any]) -> str:
    return json.dumps(config, sort_keys=True)


class Experiments:
    """Submits every group, waits for them, and keeps what the API says of each run."""

    def __init__(self, client: Client, plan: Plan, resume: bool = False) -> None:
        self.client = client
        self.plan = plan
        self.groups: list[Group] = []
        self.sweep_id: int | None = None
        self.clock_sweep_id: int | None = None
        self.reused = 0
        self._curves: dict[int, list[dict[str, Any]]] = {}
        self._latest: dict[int, dict[str, Any]] = {}  # run id -> the API's last word on it
        self._finished: set[int] = set()  # runs in a final state: never asked for again
        # with resume: runs not in a sweep, by resolved config, and sweeps, by request
        self._runs: dict[str, list[int]] = {}
        self._sweeps: list[dict[str, Any]] = []
        if resume:
            self._index_existing()

    def _all_runs(self) -> Iterator[dict[str, Any]]:
        """Every run the service holds, newest first, 200 to a request."""
        return self.client.runs(page=200)

    def _index_existing(self) -> None:
        """What the service already holds that a resumed reproduction may reuse: every run
        that has not failed or been cancelled (a queued or running one finishes by itself)."""
        sweep_ids: set[int] = set()
        for run in self._all_runs():
            if run["status"] in {RunStatus.FAILED, RunStatus.CANCELLED}:
                continue
            if run.get("sweep_id") is not None:
                sweep_ids.add(run["sweep_id"])
            else:
                self._runs.setdefault(_key(run["config"]), []).append(run["id"])
        for ids in self._runs.values():
            ids.sort()
        self._sweeps = [self.client.get_sweep(i).status() for i in sorted(sweep_ids)]

    def submit_run(self, group: Group, request: dict[str, Any]) -> None:
        reusable = self._runs.get(_key(resolve(request).model_dump(mode="json")))
        if reusable:
            group.run_ids.append(reusable.pop(0))
            self.reused += 1
            return
        group.run_ids.append(self.client.run(**request).id)

    def submit_sweep(self, request: dict[str, Any]) -> dict[str, Any]:
        for sweep in self._sweeps:
            statuses = [s for box in sweep["boxes"] for s in box["statuses"]]
            if sweep["request"] == request and not {RunStatus.FAILED, RunStatus.CANCELLED} & set(
                statuses
            ):
                self._sweeps.remove(sweep)
                self.reused += len(statuses)
                return sweep
        return self.client.sweep(**request).data

    def sweep_groups(self, name: tuple[str, str], request: dict[str, Any]) -> int:
        """The plan's boxes and seeds as one sweep of `request`, a group per box; its id."""
        plan = self.plan
        sweep = self.submit_sweep(
            {**request, "shapes": [list(s) for s in plan.boxes], "seeds": plan.seeds}
        )
        for box in sweep["boxes"]:
            group = Group(*name, tuple(box["shape"]))
            group.run_ids = list(box["run_ids"])
            self.groups.append(group)
        return int(sweep["id"])

    def submit_all(self) -> None:
        plan = self.plan
        self.sweep_id = self.sweep_groups(("boxes", "paper-voxel"), plan.voxel)
        sim = {**plan.voxel.get("sim", {}), **plan.clock_sim}
        self.clock_sweep_id = self.sweep_groups(CLOCK, {**plan.voxel, "sim": sim})
        cube = Group("phase 2", "paper-cube", (1, 1, 1))
        for seed in plan.seeds:
            self.submit_run(cube, {**plan.cube, "seed": seed})
        self.groups.append(cube)
        for shape in plan.encoding_boxes:
            spring = Group("encodings", "spring", shape)
            for seed in plan.seeds:
                self.submit_run(
                    spring, {**plan.voxel, "encoding": "spring", "shape": list(shape), "seed": seed}
                )
            self.groups.append(spring)
        focus = Group(*GA_ON_FOCUS, plan.focus)
        swept = {
            self.client.get_run(i).status()["seed"]: i
            for i in self.group("boxes", "paper-voxel", plan.focus).run_ids
        }
        for seed in plan.focus_seeds:
            if seed in swept:  # the sweep's run of this seed
                focus.run_ids.append(swept[seed])
            else:
                self.submit_run(focus, {**plan.voxel, "shape": list(plan.focus), "seed": seed})
        self.groups.append(focus)
        for name, overrides in plan.ablation.items():
            group = Group("ablation", name, plan.focus)
            for seed in plan.focus_seeds:
                self.submit_run(
                    group, {**plan.voxel, **overrides, "shape": list(plan.focus), "seed": seed}
                )
            self.groups.append(group)

    def submit_baselines(self, budget: float) -> None:
        """Random search and the hill climber, stopped at the GA's mean evaluation count."""
        plan = self.plan
        population = int(plan.voxel.get("population", 25))
        reference = Group("baselines", "GA (paper-voxel)", plan.focus)
        reference.run_ids = list(self.group(*GA_ON_FOCUS, plan.focus).run_ids)
        random_search = Group("baselines", "random search", plan.focus)
        climber = Group("baselines", "hill climber", plan.focus)
        for seed in plan.focus_seeds:
            self.submit_run(
                random_search,
                {
                    **plan.voxel,
                    "algorithm": "random",
                    "shape": list(plan.focus),
                    "seed": seed,
                    "population": population,
                    "generations": max(1, round(budget / population)),
                },
            )
            self.submit_run(
                climber,
                {
                    **plan.voxel,
                    "algorithm": "hillclimb",
                    "shape": list(plan.focus),
                    "seed": seed,
                    "population": plan.climbers,
                    "generations": max(
                        1, round(1 + (budget - plan.climbers) / (plan.climbers - 1))
                    ),
                },
            )
        self.groups += [reference, random_search, climber]

    def refresh(self) -> None:
        """Every group's runs as the API has them now. A finished run is kept, not asked for
        again; the rest come from the run listing (newest first, so ours come first, 200 to a
        request) rather than one request per run every round."""
        wanted = {i for g in self.groups for i in g.run_ids if i not in self._finished}
        for run in self._all_runs() if wanted else ():
            if run["id"] in wanted:
                wanted.discard(run["id"])
                self._latest[run["id"]] = run
            if not wanted:
                break
        for run_id in wanted:  # not listed (yet): ask for it alone
            self._latest[run_id] = self.client.get_run(run_id).status()
        for run_id, run in self._latest.items():
            if run["status"] in FINAL:
                self._finished.add(run_id)
        for group in self.groups:
            group.runs = [self._latest[i] for i in group.run_ids]

    def wait(self) -> None:
        started = time.monotonic()
        baselines = False
        last = ""
        while True:
            self.refresh()
            focus = self.group(*GA_ON_FOCUS, self.plan.focus)
            if not baselines and all(r["status"] in FINAL for r in focus.runs):
                budget = statistics.fmean(r["progress"]["evaluations"] for r in focus.runs)
                self.submit_baselines(budget)
                baselines = True
                continue
            runs = list({r["id"]: r for g in self.groups for r in g.runs}.values())
            done = sum(r["status"] in FINAL for r in runs)
            line = f"{done}/{len(runs)} runs done"
            if line != last:
                print(f"  {time.monotonic() - started:7.0f} s  {line}", flush=True)
                last = line
            if baselines and done == len(runs):
                return
            time.sleep(2)

    def group(self, experiment: str, variant: str, shape: tuple[int, int, int]) -> Group:
        for group in self.groups:
            if (group.experiment, group.variant, group.shape) == (experiment, variant, shape):
                return group
        raise KeyError((experiment, variant, shape))

    def curve(self, run_id: int) -> list[dict[str, Any]]:
        if run_id not in self._curves:
            self._curves[run_id] = self.client.get_run(run_id).curve()
        return self._curves[run_id]

    def budget(self, group: Group) -> float | None:
        """The mean simulations of the GA at the paper's settings that `group` is compared
        with: the focus box's GA (all focus seeds) for the baselines and the ablation, the
        sweep's box for the encodings; None for the GA itself, the boxes and phase 2."""
        if group.variant in REFERENCES:
            return None
        if group.experiment in {"ablation", "baselines"}:
            runs = self.group(*GA_ON_FOCUS, group.shape).runs
        elif group.experiment == "encodings":
            runs = self.group("boxes", "paper-voxel", group.shape).runs
        else:
            return None
        return statistics.fmean(r["progress"]["evaluations"] for r in runs) if runs else None

    def best_within(self, run_id: int, budget: float) -> float | None:
        """Best so far after the last generation that kept the run's simulations within
        `budget`, so a variant that simulates more than the GA is compared on equal terms."""
        best, total = None, 0
        for row in self.curve(run_id):
            total += row["evaluations"]
            if total > budget:
                break
            best = row["best_so_far"]
        return best

    def rows(self) -> list[dict[str, Any]]:
        """The table: one row per group, and for the groups that are compared with the GA
        (baselines, encodings, ablation) their best within the GA's budget on the same box."""
        rows = []
        for group in self.groups:
            row = {**group.row(), "budget": None, "budget_best_mean": None, "budget_best_std": None}
            budget = self.budget(group)
            if budget is not None:
                best = [self.best_within(r["id"], budget) for r in group.runs]
                known = [b for b in best if b is not None]
                row["budget"] = budget
                if known:
                    row["budget_best_mean"] = statistics.fmean(known)
                    row["budget_best_std"] = statistics.pstdev(known)
            rows.append(row)
        return rows

    def busy(self) -> float:
        """Wall seconds during which at least one run was going (the union of the runs' start
        to finish intervals, from the API's timestamps): a resumed reproduction's idle gaps
        between invocations do not count."""
        spans = sorted(
            (datetime.fromisoformat(r["started_at"]), datetime.fromisoformat(r["finished_at"]))
            for g in self.groups
            for r in g.runs
            if r.get("started_at") and r.get("finished_at")
        )
        total, end = 0.0, None
        for start, finish in spans:
            if end is None or start > end:
                total += (finish - start).total_seconds()
                end = finish
            elif finish > end:
                total += (finish - end).total_seconds()
                end = finish
        return total

    def individuals(self, run_id: int) -> list[dict[str, Any]]:
        return self.client.get_run(run_id).individuals()
