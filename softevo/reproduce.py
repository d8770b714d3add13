"""`softevo reproduce`: the paper's experiments, and past them, run through the service's API.

Everything that evolves goes through the REST API: the nine bounding boxes as one sweep
(`POST /sweeps`), the phase 2 cube, the baselines (random search and a hill climber on the GA's
measured evaluation budget), the `spring` encoding against `voxel`, and an ablation of the
paper's GA settings. Without `--url` a private `softevo serve` (SQLite in the output folder, the
in-process pool on every core) is started and stopped here. Phase 1, the breathing cube, is one
robot, not an evolution: it is simulated in this process with `core.physics`.

Outputs in `--out`: results.csv and results.md (one row per experiment, variant and box: best
speed over seeds, best within the GA's simulation budget, evaluations, wall time), the figures as
PNG, and softevo.db with every genome. `--resume` reuses the runs a previous invocation left in
that database (or in the `--url` service) and submits only what is missing, so an interrupted
reproduction goes on where it stopped, and the tables and figures can be redrawn from finished
runs without simulating anything again (every run is deterministic in its config and seed).
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import json
import math
import os
import socket
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any

import httpx

from softevo.core import figures
from softevo.core.config import resolve
from softevo.core.status import FINAL as FINAL_STATUSES
from softevo.core.status import RunStatus

PAPER_NINE = [
    (3, 3, 6),
    (4, 4, 3),
    (4, 4, 4),
    (5, 5, 3),
    (5, 5, 4),
    (5, 5, 5),
    (6, 6, 3),
    (6, 6, 6),
    (9, 9, 2),
]
FINAL = {str(status) for status in FINAL_STATUSES}
#: 2 pi rad/s: one actuation period a second, 9 in paper-voxel's clock (1.4 at the paper's 1 rad/s)
FAST_OMEGA = 2 * math.pi
CLOCK = ("clock", "omega 2pi")  # the boxes' sweep again at FAST_OMEGA
GA_ON_FOCUS = ("ablation", "paper settings")  # the GA at the paper's settings on the focus box
REFERENCES = {"paper settings", "GA (paper-voxel)"}  # the GA rows others are compared with


@dataclass(frozen=True)
class Plan:
    """What to run: the full reproduction, or a tiny one with the same code path (`--quick`)."""

    boxes: list[tuple[int, int, int]]
    seeds: list[int]
    voxel: dict[str, Any]  # the paper-voxel request every voxel experiment starts from
    cube: dict[str, Any]  # the phase 2 request
    focus: tuple[int, int, int]  # the box of the baselines and the ablation
    encoding_boxes: list[tuple[int, int, int]]
    ablation: dict[str, dict[str, Any]]
    climbers: int = 5  # hill climber population: the best and 4 mutants per generation
    # more seeds on the focus box (GA, baselines, ablation): its comparisons are the noisiest
    extra_focus_seeds: list[int] = field(default_factory=list)
    # the boxes again with a faster actuation, so the fitness clock spans many periods
    clock_sim: dict[str, Any] = field(default_factory=lambda: {"omega": FAST_OMEGA})

    @property
    def focus_seeds(self) -> list[int]:
        return self.seeds + [s for s in self.extra_focus_seeds if s not in self.seeds]


FULL = Plan(
    boxes=PAPER_NINE,
    seeds=[1, 2, 3],
    voxel={"preset": "paper-voxel"},
    cube={"preset": "paper-cube"},
    focus=(4, 4, 4),
    encoding_boxes=PAPER_NINE,
    ablation={
        "tournament selection": {"selection": "tournament"},
        "mutation 0.5": {"mutation_probability": 0.5},
        "no immigrants": {"immigrants": 0.0},
    },
    extra_focus_seeds=[4, 5],
)
QUICK = Plan(
    boxes=[(2, 2, 2), (3, 2, 2)],
    seeds=[1, 2],
    voxel={
        "preset": "paper-voxel",
        "population": 6,
        "generations": 3,
        "sim": {"duration": 1.0, "settle_time": 0.3},
    },
    cube={
        "preset": "paper-cube",
        "population": 6,
        "generations": 3,
        "sim": {"duration": 1.0, "settle_time": 0.3},
    },
    focus=(2, 2, 2),
    encoding_boxes=[(2, 2, 2)],
    ablation={"mutation 0.5": {"mutation_probability": 0.5}},
    climbers=3,
    extra_focus_seeds=[3],
)


def add_parser(commands: Any) -> None:
    parser = commands.add_parser(
        "reproduce",
        help="re-run the paper's experiments (and baselines, encodings, an ablation) via the API",
        description=(
            "Run the paper's nine bounding boxes (paper-voxel, seeds 1-3, one sweep), its phase "
            "2 cube and phase 1 breathing cube, random search and hill-climber baselines on the "
            "GA's evaluation budget, the spring encoding against voxel, and an ablation of the "
            "GA's settings, all through the REST API; write results.csv, results.md and the "
            "figures into --out. --quick runs a tiny version of all of it in under a minute."
        ),
    )
    parser.add_argument("--quick", action="store_true", help="tiny settings, same code path")
    parser.add_argument("--out", default="docs/experiments", help="output folder")
    parser.add_argument(
        "--url", help="a running service (token from SOFTEVO_API_TOKEN); default: start one"
    )
    parser.add_argument(
        "--workers", type=int, help="pool processes of the private service (default: all cores)"
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help="reuse matching runs already in --out/softevo.db (or the --url service) instead of "
        "starting afresh; submit only the missing ones",
    )
    parser.set_defaults(handler=reproduce_command)


# -- the service ---------------------------------------------------------------------------------


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@contextlib.contextmanager
def service(
    url: str | None, out: Path, workers: int | None, resume: bool = False
) -> Iterator[httpx.Client]:
    """A client of `url`, or of a private `softevo serve` on a SQLite file in `out` (kept with
    `resume`, else started afresh)."""
    token = os.environ.get("SOFTEVO_API_TOKEN")
    headers = {"Authorization": f"Bearer {token}"} if token else {}
    if url:
        with httpx.Client(base_url=url, headers=headers, timeout=60) as client:
            yield client
        return
    database = out / "softevo.db"
    if not resume:
        for stale in out.glob("softevo.db*"):
            stale.unlink()
    port = _free_port()
    env = {
        **os.environ,
        "SOFTEVO_DATABASE_URL": f"sqlite:///{database}",
        "SOFTEVO_MAX_RUNNING": "2",
        "SOFTEVO_MAX_QUEUED": "10000",
    }
    env.pop("SOFTEVO_REDIS_URL", None)
    env.pop("SOFTEVO_API_TOKEN", None)
    if workers:
        env["SOFTEVO_WORKERS"] = str(workers)
    log = (out / "service.log").open("wb")
    # -P: the current directory does not go first on the path, so a folder there named `softevo`
    # (a clone, say) cannot stand in for the installed package.
    process = subprocess.Popen(
        [
            sys.executable,
            "-P",
            "-m",
            "softevo.cli",
            "serve",
            "--port",
            str(port),
            "--log-level",
            "warning",
        ],
        env=env,
        stdout=log,
        stderr=subprocess.STDOUT,
    )
    try:
        with httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=60) as client:
            deadline = time.monotonic() + 120
            while True:
                if process.poll() is not None:
                    raise SystemExit(f"softevo reproduce: the service exited; see {log.name}")
                with contextlib.suppress(httpx.TransportError):
                    if client.get("/healthz").status_code == 200:
                        break
                if time.monotonic() > deadline:
                    raise SystemExit("softevo reproduce: the service did not start in 120 s")
                time.sleep(0.2)
            yield client
    finally:
        process.terminate()
        try:
            process.wait(30)
        except subprocess.TimeoutExpired:
            process.kill()
        log.close()


def _check(response: httpx.Response) -> Any:
    if response.status_code >= 400:
        raise SystemExit(
            f"softevo reproduce: {response.request.method} {response.request.url.path} "
            f"answered {response.status_code}: {response.text[:500]}"
        )
    return response.json()


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
        walls = [_wall(r) for r in self.runs]
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


def _wall(run: dict[str, Any]) -> float:
    if not run.get("started_at") or not run.get("finished_at"):
        return math.nan
    started = datetime.fromisoformat(run["started_at"])
    return (datetime.fromisoformat(run["finished_at"]) - started).total_seconds()


def _key(config: dict[str, Any]) -> str:
    return json.dumps(config, sort_keys=True)


class Experiments:
    """Submits every group, waits for them, and keeps what the API says of each run."""

    def __init__(self, client: httpx.Client, plan: Plan, resume: bool = False) -> None:
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
        offset = 0
        while True:
            page = _check(self.client.get("/runs", params={"offset": offset, "limit": 200}))
            yield from page["items"]
            offset += len(page["items"])
            if not page["items"] or offset >= page["total"]:
                return

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
        self._sweeps = [_check(self.client.get(f"/sweeps/{i}")) for i in sorted(sweep_ids)]

    def submit_run(self, group: Group, request: dict[str, Any]) -> None:
        reusable = self._runs.get(_key(resolve(request).model_dump(mode="json")))
        if reusable:
            group.run_ids.append(reusable.pop(0))
            self.reused += 1
            return
        run = _check(self.client.post("/runs", json=request))
        group.run_ids.append(run["id"])

    def submit_sweep(self, request: dict[str, Any]) -> dict[str, Any]:
        for sweep in self._sweeps:
            statuses = [s for box in sweep["boxes"] for s in box["statuses"]]
            if sweep["request"] == request and not {RunStatus.FAILED, RunStatus.CANCELLED} & set(
                statuses
            ):
                self._sweeps.remove(sweep)
                self.reused += len(statuses)
                return sweep
        return _check(self.client.post("/sweeps", json=request))

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
            _check(self.client.get(f"/runs/{i}"))["seed"]: i
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
            self._latest[run_id] = _check(self.client.get(f"/runs/{run_id}"))
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
            self._curves[run_id] = _check(self.client.get(f"/runs/{run_id}/curve"))["generations"]
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
                best = [b for b in best if b is not None]
                row["budget"] = budget
                if best:
                    row["budget_best_mean"] = statistics.fmean(best)
                    row["budget_best_std"] = statistics.pstdev(best)
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
        items: list[dict[str, Any]] = []
        while True:
            page = _check(
                self.client.get(
                    f"/runs/{run_id}/individuals", params={"offset": len(items), "limit": 5000}
                )
            )
            items += page["items"]
            if not page["items"] or len(items) >= page["total"]:
                return items


# -- phase 1 ---------------------------------------------------------------------------------------


def breathing_cube(out: Path, quick: bool) -> dict[str, Any]:
    """The paper's phase 1: the shipped breathing cube, simulated here (one robot, no evolution)."""
    from softevo.core.physics import simulate
    from softevo.core.robot_file import load_robot, with_sim

    robot = load_robot(Path(__file__).resolve().parent.parent / "examples" / "breathing_cube.json")
    if quick:
        robot = with_sim(robot, duration=2.0)
    result, trajectory = simulate(robot, record_every=max(1, round(1 / (100 * robot.sim.dt))))
    assert trajectory is not None
    heights = trajectory.frames[:, :, 2].mean(axis=1)
    xs = trajectory.frames[:, :, 0].mean(axis=1)
    plt = figures.pyplot()
    figure, axes = plt.subplots(figsize=(5.5, 3.0))
    axes.plot(trajectory.times, heights, label="centre of mass height (m)")
    axes.plot(trajectory.times, xs - xs[0], label="centre of mass x shift (m)")
    axes.set_xlabel("time (s)")
    axes.set_title("phase 1: the breathing cube dropped onto the ground")
    axes.legend(frameon=False)
    figure.tight_layout()
    figures.save(figure, out / "phase1_breathing_cube.png")
    return {
        "speed": result.speed,
        "distance": result.distance,
        "stable": result.stable,
        "final_height": float(heights[-1]),
        "duration": robot.sim.duration,
    }


# -- the champions, simulated for longer ----------------------------------------------------------

LONGER = (1, 3, 6)  # multiples of the run's simulated time


def champions(experiments: Experiments, out: Path) -> list[dict[str, Any]]:
    """The fastest robot of each box, at the paper's actuation and at FAST_OMEGA
    (`GET /runs/{id}/best`, saved as best_<box>.json and best_fast_<box>.json), simulated in
    this process for 1x (the fitness the run stored, as a check), 3x and 6x the run's time: a
    fitness clock of a few actuation periods can reward a transient lunge, and this shows
    which robots keep their speed."""
    from softevo.core.physics import simulate
    from softevo.core.robot_file import parse_robot, with_sim

    rows = []
    for (experiment, variant), prefix in (
        ((("boxes", "paper-voxel")), "best"),
        (CLOCK, "best_fast"),
    ):
        for shape in experiments.plan.boxes:
            group = experiments.group(experiment, variant, shape)
            done = [r for r in group.runs if r["progress"]["best_fitness"] is not None]
            if not done:
                continue
            run = max(done, key=lambda r: r["progress"]["best_fitness"])
            data = _check(experiments.client.get(f"/runs/{run['id']}/best"))
            box = "x".join(map(str, shape))
            (out / f"{prefix}_{box}.json").write_text(json.dumps(data, indent=1) + "\n")
            robot = parse_robot(data)
            row: dict[str, Any] = {
                "experiment": experiment,
                "omega": robot.sim.omega,
                "shape": box,
                "run": run["id"],
                "seed": run["seed"],
                "stored_best": run["progress"]["best_fitness"],
                "voxels": sum(label != "empty" for label in data["voxels"]),
            }
            for factor in LONGER:
                duration = robot.sim.duration * factor
                result, _ = simulate(with_sim(robot, duration=duration))
                row[f"speed_{factor}x"] = result.speed
                row[f"duration_{factor}x"] = duration
            rows.append(row)
    with (out / "champions.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]) if rows else ["shape"])
        writer.writeheader()
        writer.writerows(rows)
    return rows


def champions_table(rows: list[dict[str, Any]]) -> list[str]:
    if not rows:
        return []
    durations = [f"{rows[0][f'duration_{f}x']:g} s" for f in LONGER]
    return [
        "## champions, simulated for longer",
        "",
        "The fastest robot of each box, at the paper's actuation (boxes) and at 2 pi rad/s "
        "(clock): best_<box>.json and best_fast_<box>.json, simulated again in process for the "
        "run's own time (the first speed must equal the stored best) and longer.",
        "",
        "| experiment | omega (rad/s) | box | run | seed | voxels | stored best (m/s) | "
        + " | ".join(f"speed over {d} (m/s)" for d in durations)
        + " |",
        "| --- | ---: | --- | ---: | ---: | ---: | ---: |" + " ---: |" * len(LONGER),
        *(
            f"| {r['experiment']} | {r['omega']:.4g} | {r['shape']} | {r['run']} | {r['seed']} "
            f"| {r['voxels']} | {_fmt(r['stored_best'])} | "
            + " | ".join(_fmt(r[f"speed_{f}x"]) for f in LONGER)
            + " |"
            for r in rows
        ),
        "",
    ]


# -- outputs ---------------------------------------------------------------------------------------

COLUMNS = [
    "experiment",
    "variant",
    "shape",
    "seeds",
    "completed",
    "best_mean",
    "best_std",
    "best_min",
    "best_max",
    "best_by_seed",
    "evaluations_mean",
    "population",
    "generations",
    "wall_seconds_mean",
    "budget",
    "budget_best_mean",
    "budget_best_std",
]


def _fmt(value: Any, digits: int = 4) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def write_tables(
    rows: list[dict[str, Any]], out: Path, notes: list[str], appendix: Sequence[str] = ()
) -> None:
    with (out / "results.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    lines = ["# softevo reproduce: results", "", *notes, ""]
    for experiment in dict.fromkeys(r["experiment"] for r in rows):
        group = [r for r in rows if r["experiment"] == experiment]
        budgeted = any(r["budget"] is not None for r in group)
        extra = " best within the GA's simulations: mean (std) | GA's simulations |"
        lines += [
            f"## {experiment}",
            "",
            "| variant | box | seeds | best speed mean (m/s) | spread (std) | min | max "
            "| simulations (mean) | wall per run (s) |" + (extra if budgeted else ""),
            "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"
            + (" ---: | ---: |" if budgeted else ""),
        ]
        for r in group:
            line = (
                f"| {r['variant']} | {r['shape']} | {r['seeds']} | {_fmt(r['best_mean'])} "
                f"| {_fmt(r['best_std'])} | {_fmt(r['best_min'])} | {_fmt(r['best_max'])} "
                f"| {_fmt(r['evaluations_mean'], 0)} | {_fmt(r['wall_seconds_mean'], 1)} |"
            )
            if budgeted:
                within = (
                    f"{_fmt(r['budget_best_mean'])} ({_fmt(r['budget_best_std'])})"
                    if r["budget_best_mean"] is not None
                    else "-"
                )
                line += f" {within} | {_fmt(r['budget'], 0)} |"
            lines.append(line)
        lines.append("")
    lines += appendix
    (out / "results.md").write_text("\n".join(lines))


def _bars(groups: list[Group], labels: list[str], title: str, path: Path) -> None:
    plt = figures.pyplot()
    figure, axes = plt.subplots(figsize=(6.5, 3.4))
    for x, group in enumerate(groups):
        best = [r["progress"]["best_fitness"] or 0.0 for r in group.runs]
        if best:
            axes.bar(x, statistics.fmean(best), color="tab:blue", alpha=0.6)
            axes.scatter([x] * len(best), best, color="black", s=10, zorder=3)
    axes.set_xticks(range(len(groups)), labels, rotation=30, ha="right")
    axes.set_ylabel("best speed (m/s)")
    axes.set_title(title)
    figure.tight_layout()
    figures.save(figure, path)


def _paired(
    experiments: Experiments,
    shapes: list[tuple[int, int, int]],
    other: tuple[str, str],
    names: tuple[str, str],
    title: str,
    path: Path,
) -> None:
    """Bars per box: the paper-voxel sweep's box, then `other`'s (experiment, variant)."""
    pairs = []
    for shape in shapes:
        pairs += [
            experiments.group("boxes", "paper-voxel", shape),
            experiments.group(*other, shape),
        ]
    labels = [
        f"{'x'.join(map(str, g.shape))} {names[0] if g.experiment == 'boxes' else names[1]}"
        for g in pairs
    ]
    _bars(pairs, labels, title, path)


def write_figures(experiments: Experiments, out: Path) -> dict[str, Any]:
    plan = experiments.plan
    boxes = [experiments.group("boxes", "paper-voxel", s) for s in plan.boxes]
    _bars(
        boxes,
        ["x".join(map(str, g.shape)) for g in boxes],
        "Figure 4(a): best speed per bounding box (bars: mean, dots: seeds)",
        out / "fig4a_boxes.png",
    )
    # Figure 4(b)-(d): the best run of the box with the best mean
    best_box = max(boxes, key=lambda g: g.row()["best_mean"] or -math.inf)
    best_run = max(best_box.runs, key=lambda r: r["progress"]["best_fitness"] or -math.inf)
    title = f"{'x'.join(map(str, best_box.shape))}, seed {best_run['seed']}"
    curve = experiments.curve(best_run["id"])
    individuals = experiments.individuals(best_run["id"])
    figures.save(
        figures.curve_figure(curve, f"Figure 4(b): learning curve, {title}"),
        out / "fig4b_curve.png",
    )
    figures.save(
        figures.population_figure(individuals, f"Figure 4(c): population, {title}"),
        out / "fig4c_population.png",
    )
    figures.save(
        figures.diversity_figure(curve, f"Figure 4(d): diversity, {title}"),
        out / "fig4d_diversity.png",
    )
    cube = experiments.group("phase 2", "paper-cube", (1, 1, 1))
    _curves(
        experiments,
        [("paper-cube", cube)],
        "phase 2: the cube's learning curves",
        out / "phase2_cube.png",
        by="generation",
    )
    baselines = [(g.variant, g) for g in experiments.groups if g.experiment == "baselines"]
    _curves(
        experiments,
        baselines,
        f"GA against baselines, {'x'.join(map(str, plan.focus))}: best so far",
        out / "baselines.png",
        by="evaluations",
    )
    _paired(
        experiments,
        plan.encoding_boxes,
        ("encodings", "spring"),
        ("voxel", "spring"),
        "voxel against spring encoding (bars: mean, dots: seeds)",
        out / "encodings.png",
    )
    _paired(
        experiments,
        plan.boxes,
        CLOCK,
        ("1 rad/s", "2 pi"),
        "the boxes at the paper's actuation (1 rad/s) and at 2 pi rad/s",
        out / "clock.png",
    )
    ablation = [g for g in experiments.groups if g.experiment == "ablation"]
    _bars(
        ablation,
        [g.variant for g in ablation],
        f"ablation, {'x'.join(map(str, plan.focus))}",
        out / "ablation.png",
    )
    _curves(
        experiments,
        [(g.variant, g) for g in ablation],
        f"ablation, {'x'.join(map(str, plan.focus))}: best so far",
        out / "ablation_curves.png",
        by="evaluations",
    )
    return {
        "figure4_run": best_run["id"],
        "figure4_box": best_box.shape,
        "figure4_seed": best_run["seed"],
    }


def _curves(
    experiments: Experiments, groups: list[tuple[str, Group]], title: str, path: Path, by: str
) -> None:
    """Best so far of every run of each group, against generation or cumulative evaluations."""
    plt = figures.pyplot()
    figure, axes = plt.subplots(figsize=(6.0, 3.4))
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:red"]
    for k, (label, group) in enumerate(groups):
        for n, run in enumerate(group.runs):
            curve = experiments.curve(run["id"])
            if by == "evaluations":
                x, total = [], 0
                for row in curve:
                    total += row["evaluations"]
                    x.append(total)
            else:
                x = [row["generation"] for row in curve]
            y = [row["best_so_far"] for row in curve]
            axes.plot(
                x,
                y,
                color=colours[k % len(colours)],
                alpha=0.8,
                marker="." if len(x) < 20 else None,
                label=label if n == 0 else None,
            )
    axes.set_xlabel("simulations" if by == "evaluations" else "generation")
    axes.set_ylabel("best so far (m/s)")
    axes.set_title(title)
    axes.legend(frameon=False)
    figure.tight_layout()
    figures.save(figure, path)


def reproduce_command(args: argparse.Namespace) -> int:
    plan = QUICK if args.quick else FULL
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / ".write-test").touch()
        (out / ".write-test").unlink()
    except OSError as error:
        args.parser.error(f"--out {out}: cannot write there ({error.strerror})")
    started = time.monotonic()
    flags = " --quick" if args.quick else ""
    print(f"softevo reproduce{flags}: results in {out}/", flush=True)
    phase1 = breathing_cube(out, args.quick)
    try:
        with service(args.url, out, args.workers, args.resume) as client:
            experiments = Experiments(client, plan, resume=args.resume)
            experiments.submit_all()
            experiments.wait()
            figure4 = write_figures(experiments, out)
            sweep = _check(client.get(f"/sweeps/{experiments.sweep_id}"))
            rows = experiments.rows()
            longer = champions(experiments, out)
    except httpx.HTTPError as error:
        where = args.url or "the private service"
        raise SystemExit(f"softevo reproduce: error: {where}: {error}") from None
    wall = time.monotonic() - started
    runs = list({r["id"]: r for g in experiments.groups for r in g.runs}.values())
    walls = [w for w in (_wall(r) for r in runs) if math.isfinite(w)]
    reused = (
        f" ({experiments.reused} of them reused from an earlier invocation by --resume)"
        if experiments.reused
        else ""
    )
    notes = [
        f"Command: `softevo reproduce{flags} --out {out}"
        + (f" --url {args.url}" if args.url else "")
        + f"`; {len(runs)} runs through the REST API{reused}, sweep {experiments.sweep_id} "
        f"holds the boxes and sweep {experiments.clock_sweep_id} the boxes at 2 pi rad/s; this "
        f"machine has {os.cpu_count()} cores.",
        f"Wall time: {experiments.busy():.0f} s with at least one run going (the union of the "
        f"runs' start-to-finish intervals, from the API); the runs' own wall times add up to "
        f"{sum(walls):.0f} s"
        + (
            "."
            if args.url
            else ", because the private service ran two at a time (SOFTEVO_MAX_RUNNING=2) on "
            "one pool of processes, so a run's wall time is about twice what it would be alone."
        )
        + f" This invocation took {wall:.0f} s.",
        "Simulations: a run's simulations (its evaluations) are the genomes it simulated; the "
        "rest of its population came from its fitness cache (survivors, repeats). The "
        "baselines were given the paper-voxel GA's mean simulations on their box; 'best within "
        "the GA's simulations' is each run's best so far at the last generation that stayed "
        "within that many, so variants that simulate more are compared on equal terms.",
        f"Phase 1 (breathing cube, simulated in process with core.physics for "
        f"{phase1['duration']:.0f} s): speed {_fmt(phase1['speed'], 5)} m/s, net distance "
        f"{_fmt(phase1['distance'], 5)} m, final centre-of-mass height "
        f"{phase1['final_height']:.4f} m, stable {phase1['stable']}.",
        f"Figure 4(b)-(d): run {figure4['figure4_run']} (box "
        f"{'x'.join(map(str, figure4['figure4_box']))}, seed {figure4['figure4_seed']}).",
        "Sweep as the API reports it (best mean per box): "
        + ", ".join(
            f"{'x'.join(map(str, b['shape']))} {_fmt(b['best_mean'])}" for b in sweep["boxes"]
        )
        + ".",
    ]
    write_tables(rows, out, notes, champions_table(longer))
    print(f"done in {wall:.0f} s: {out / 'results.md'}")
    return 0
