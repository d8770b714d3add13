"""`softevo reproduce`: the paper's experiments, and past them, run through the service's API.

Everything that evolves goes through the REST API: the nine bounding boxes as one sweep
(`POST /sweeps`), the phase 2 cube, the baselines (random search and a hill climber on the GA's
measured evaluation budget), the `spring` encoding against `voxel`, and an ablation of the
paper's GA settings. Without `--url` a private `softevo serve` (SQLite in the output folder, the
in-process pool on every core) is started and stopped here. Phase 1, the breathing cube, is one
robot, not an evolution: it is simulated in this process with `core.physics`.

Outputs in `--out`: results.csv and results.md (one row per experiment, variant and box: best
speed over seeds, evaluations, wall time), the figures as PNG, and softevo.db with every genome.
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import math
import os
import socket
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any

import httpx

from core import figures

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
FINAL = {"completed", "failed", "cancelled"}


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


FULL = Plan(
    boxes=PAPER_NINE,
    seeds=[1, 2, 3],
    voxel={"preset": "paper-voxel"},
    cube={"preset": "paper-cube"},
    focus=(4, 4, 4),
    encoding_boxes=[(4, 4, 3), (4, 4, 4), (5, 5, 3)],
    ablation={
        "tournament selection": {"selection": "tournament"},
        "mutation 0.5": {"mutation_probability": 0.5},
        "no immigrants": {"immigrants": 0.0},
    },
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
    parser.set_defaults(handler=reproduce_command)


# -- the service ---------------------------------------------------------------------------------


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@contextlib.contextmanager
def service(url: str | None, out: Path, workers: int | None) -> Iterator[httpx.Client]:
    """A client of `url`, or of a private `softevo serve` on a SQLite file in `out`."""
    token = os.environ.get("SOFTEVO_API_TOKEN")
    headers = {"Authorization": f"Bearer {token}"} if token else {}
    if url:
        with httpx.Client(base_url=url, headers=headers, timeout=60) as client:
            yield client
        return
    database = out / "softevo.db"
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
    process = subprocess.Popen(
        [
            sys.executable,
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
        best = [r["progress"]["best_fitness"] for r in self.runs if r["status"] == "completed"]
        best = [b for b in best if b is not None]
        walls = [_wall(r) for r in self.runs]
        return {
            "experiment": self.experiment,
            "variant": self.variant,
            "shape": "x".join(map(str, self.shape)),
            "seeds": " ".join(str(r["seed"]) for r in self.runs),
            "completed": sum(r["status"] == "completed" for r in self.runs),
            "best_mean": statistics.fmean(best) if best else None,
            "best_std": statistics.pstdev(best) if best else None,
            "best_min": min(best) if best else None,
            "best_max": max(best) if best else None,
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


class Experiments:
    """Submits every group, waits for them, and keeps what the API says of each run."""

    def __init__(self, client: httpx.Client, plan: Plan) -> None:
        self.client = client
        self.plan = plan
        self.groups: list[Group] = []
        self.sweep_id: int | None = None

    def submit_run(self, group: Group, request: dict[str, Any]) -> None:
        run = _check(self.client.post("/runs", json=request))
        group.run_ids.append(run["id"])

    def submit_all(self) -> None:
        plan = self.plan
        sweep = _check(
            self.client.post(
                "/sweeps",
                json={**plan.voxel, "shapes": [list(s) for s in plan.boxes], "seeds": plan.seeds},
            )
        )
        self.sweep_id = sweep["id"]
        for box in sweep["boxes"]:
            group = Group("boxes", "paper-voxel", tuple(box["shape"]))
            group.run_ids = list(box["run_ids"])
            self.groups.append(group)
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
        for name, overrides in plan.ablation.items():
            group = Group("ablation", name, plan.focus)
            for seed in plan.seeds:
                self.submit_run(
                    group, {**plan.voxel, **overrides, "shape": list(plan.focus), "seed": seed}
                )
            self.groups.append(group)

    def submit_baselines(self, budget: float) -> None:
        """Random search and the hill climber, stopped at the GA's mean evaluation count."""
        plan = self.plan
        population = int(plan.voxel.get("population", 25))
        random_search = Group("baselines", "random search", plan.focus)
        climber = Group("baselines", "hill climber", plan.focus)
        for seed in plan.seeds:
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
        self.groups += [random_search, climber]

    def wait(self) -> None:
        started = time.monotonic()
        baselines = False
        last = ""
        while True:
            for group in self.groups:
                group.runs = [_check(self.client.get(f"/runs/{i}")) for i in group.run_ids]
            focus = self.group("boxes", "paper-voxel", self.plan.focus)
            if not baselines and all(r["status"] in FINAL for r in focus.runs):
                budget = statistics.fmean(r["progress"]["evaluations"] for r in focus.runs)
                self.submit_baselines(budget)
                baselines = True
                continue
            runs = [r for g in self.groups for r in g.runs]
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
        return _check(self.client.get(f"/runs/{run_id}/curve"))["generations"]

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
    from core.physics import simulate
    from core.robot_file import load_robot, with_sim

    robot = load_robot(Path(__file__).resolve().parent.parent / "examples" / "breathing_cube.json")
    if quick:
        robot = with_sim(robot, duration=2.0)
    result, trajectory = simulate(robot, record_every=max(1, round(1 / (100 * robot.sim.dt))))
    assert trajectory is not None
    heights = trajectory.frames[:, :, 2].mean(axis=1)
    xs = trajectory.frames[:, :, 0].mean(axis=1)
    plt = figures._pyplot()
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
    "evaluations_mean",
    "population",
    "generations",
    "wall_seconds_mean",
]


def _fmt(value: Any, digits: int = 4) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def write_tables(rows: list[dict[str, Any]], out: Path, notes: list[str]) -> None:
    with (out / "results.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    lines = ["# softevo reproduce: results", "", *notes, ""]
    for experiment in dict.fromkeys(r["experiment"] for r in rows):
        lines += [
            f"## {experiment}",
            "",
            "| variant | box | seeds | best speed mean (m/s) | spread (std) | min | max "
            "| evaluations (mean) | wall per run (s) |",
            "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |",
        ]
        for r in rows:
            if r["experiment"] == experiment:
                lines.append(
                    f"| {r['variant']} | {r['shape']} | {r['seeds']} | {_fmt(r['best_mean'])} "
                    f"| {_fmt(r['best_std'])} | {_fmt(r['best_min'])} | {_fmt(r['best_max'])} "
                    f"| {_fmt(r['evaluations_mean'], 0)} | {_fmt(r['wall_seconds_mean'], 1)} |"
                )
        lines.append("")
    (out / "results.md").write_text("\n".join(lines))


def _bars(groups: list[Group], labels: list[str], title: str, path: Path) -> None:
    plt = figures._pyplot()
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
    focus = experiments.group("boxes", "paper-voxel", plan.focus)
    baselines = [("GA (paper-voxel)", focus)] + [
        (g.variant, g) for g in experiments.groups if g.experiment == "baselines"
    ]
    _curves(
        experiments,
        baselines,
        f"GA against baselines, {'x'.join(map(str, plan.focus))}: best so far",
        out / "baselines.png",
        by="evaluations",
    )
    pairs = []
    for shape in plan.encoding_boxes:
        pairs += [
            experiments.group("boxes", "paper-voxel", shape),
            experiments.group("encodings", "spring", shape),
        ]
    _bars(
        pairs,
        [
            f"{'x'.join(map(str, g.shape))} {'voxel' if g.experiment == 'boxes' else 'spring'}"
            for g in pairs
        ],
        "voxel against spring encoding",
        out / "encodings.png",
    )
    ablation = [focus] + [g for g in experiments.groups if g.experiment == "ablation"]
    _bars(
        ablation,
        ["paper settings"] + [g.variant for g in ablation[1:]],
        f"ablation, {'x'.join(map(str, plan.focus))}",
        out / "ablation.png",
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
    plt = figures._pyplot()
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
    print(f"softevo reproduce{' --quick' if args.quick else ''}: results in {out}/", flush=True)
    phase1 = breathing_cube(out, args.quick)
    with service(args.url, out, args.workers) as client:
        experiments = Experiments(client, plan)
        experiments.submit_all()
        experiments.wait()
        figure4 = write_figures(experiments, out)
        sweep = _check(client.get(f"/sweeps/{experiments.sweep_id}"))
    wall = time.monotonic() - started
    rows = [group.row() for group in experiments.groups]
    notes = [
        f"Command: `softevo reproduce{' --quick' if args.quick else ''} --out {out}`; "
        f"{len([r for g in experiments.groups for r in g.runs])} runs through the REST API "
        f"(sweep {experiments.sweep_id} holds the boxes), {wall:.0f} s of wall time on "
        f"{os.cpu_count()} cores.",
        f"Phase 1 (breathing cube, simulated in process for {phase1['duration']:.0f} s): speed "
        f"{_fmt(phase1['speed'], 5)} m/s, net distance {_fmt(phase1['distance'], 5)} m, final "
        f"centre-of-mass height {phase1['final_height']:.4f} m, stable {phase1['stable']}.",
        f"Figure 4(b)-(d): run {figure4['figure4_run']} (box "
        f"{'x'.join(map(str, figure4['figure4_box']))}, seed {figure4['figure4_seed']}).",
        "Sweep as the API reports it (best mean per box): "
        + ", ".join(
            f"{'x'.join(map(str, b['shape']))} {_fmt(b['best_mean'])}" for b in sweep["boxes"]
        )
        + ".",
    ]
    write_tables(rows, out, notes)
    print(f"done in {wall:.0f} s: {out / 'results.md'}")
    return 0
