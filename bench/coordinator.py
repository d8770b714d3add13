"""The coordinator's own cost: `python bench/coordinator.py [--generations G] [--sim-seconds S]
[--tree PATH]`.

Drives `paper-voxel` runs (4x4x4, population 25) through the service's `Coordinator` on SQLite
and on PostgreSQL with an evaluator that simulates nothing (a robot's fitness is a cheap function
of its file; a batch sleeps S seconds per robot, 0.05 by default, as a worker's wall time). Its
batches come back as a real job's do: the job function's JSON output (with each robot's record of
measures and, where the tree's job sends it, the record's text by the tree's own `record_text`;
or its heading in a tree of the release before records) turned into a `BatchResult` by the
tree's own `BatchResult.measured`, so each tree's coordinator pays for what it keeps. The CPU
seconds of the run's process, less the stand-in's own work (its fitness arithmetic and output: a
worker's, timed with `thread_time`), are the coordinator's: breeding, robot files, batches, the
store's writes and the generation commits. Each run is a fresh interpreter, warmed up by a short
run first, and freezes its heap once the coordinator has started (`gc.freeze()`), as the
service does at start-up in both trees (`api.app`): otherwise a full pass of the cyclic
collector over the start-up heap (40-55 ms here) falls inside one tree's measured run and not
the other's by the phase of the collector's counters. Prints CPU per individual (ms), wall time
per generation and generations of 25 committed per second.

`--algorithms ga,map-elites` measures MAP-Elites runs (descriptors voxels and actuated, 10 x 10
cells) interleaved with the GA's and prints MAP-Elites' CPU per individual against the GA's.

`--tree PATH` also measures another checkout (an older commit in a `git worktree`, of today's
layout or of the old one with top-level `core` and `api`), its runs interleaved with this
checkout's in the same invocation, and prints the ratio: the same runs, the same evaluator, each
version's own coordinator and store; with `--algorithms map-elites`, of MAP-Elites runs.
"""

from __future__ import annotations

import argparse
import atexit
import gc
import importlib
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))  # bench/staged.py (run with -P)
POSTGRES = os.environ.get("SOFTEVO_TEST_POSTGRES", "postgresql://postgres@127.0.0.1:5432/test")


def modules(tree: str | None) -> dict[str, Any]:
    """The coordinator, database and run creation of this checkout, or of the one at `tree`."""
    if tree is not None and (Path(tree) / "api" / "storage.py").exists():  # the old layout
        sys.path.insert(0, tree)
        prefix, store = "", "api.storage"
    else:  # this checkout, or a staged one first on the path
        prefix, store = "softevo.", "softevo.api.store"
    load = importlib.import_module
    try:  # the job's encoder of a record's text, in a tree whose job sends it
        record_text = getattr(load(f"{prefix}core.nulls"), "record_text", None)
    except ImportError:
        record_text = None
    return {
        "record_text": record_text,
        "Coordinator": load(f"{prefix}api.coordinator").Coordinator,
        "db": load(f"{prefix}api.db"),
        "create_run": load(store).create_run,
        "get_run": load(store).get_run,
        "resolve": load(f"{prefix}core.config").resolve,
        "BatchResult": load(f"{prefix}core.evaluator").BatchResult,
    }


def instant_evaluator(found: dict[str, Any], sim_seconds: float = 0.0) -> Any:
    """Both generations of the evaluator interface (`evaluate_batch` + `capacity` now;
    `evaluate_batch`, `evaluate`, `workers` and `concurrency` before), no simulation: a batch
    sleeps `sim_seconds` per robot (wall time as a worker's, none of this process's CPU)."""
    batch_result = found["BatchResult"]
    fields = getattr(batch_result, "__dataclass_fields__", {})
    form = "measures" if "measures" in fields else "heading" if "heading" in fields else None
    record_text = found["record_text"] if form == "measures" else None

    class Instant:
        concurrency = 2

        def evaluate(self, files: list[dict]) -> np.ndarray:
            return np.array([0.0 if v is None else v for v in self.job(files)["fitness"]])

        def job(self, files: list[dict]) -> dict[str, list[Any]]:
            """What the job function sends back, in the tree's own form (`job_output`)."""
            if sim_seconds:
                time.sleep(sim_seconds * len(files))
            started = time.thread_time()  # the fitness arithmetic is a worker's, not this
            fitness = [  # process's: its CPU is taken out of the figure (`drive`)
                (f["voxels"].count("sine") + f["voxels"].count("neg_sine")) / len(f["voxels"])
                for f in files
            ]
            output = job_output(fitness, form, record_text)
            with STAND_IN_LOCK:
                STAND_IN_CPU[0] += time.thread_time() - started
            return output

        def evaluate_batch(self, files: list[dict], key: str | None = None) -> Any:
            if form is None:  # a tree whose results hold fitness alone
                return batch_result(self.evaluate(files), "instant", 0.0)
            return batch_result.measured(self.job(files), "instant", 0.0)  # as a real backend

        def capacity(self) -> int:
            return 2

        workers = capacity

        def close(self) -> None:
            pass

        def __enter__(self) -> Instant:
            return self

        def __exit__(self, *exc: object) -> None:
            pass

    if hasattr(sys.modules.get(batch_result.__module__), "Evaluator"):
        base = sys.modules[batch_result.__module__].Evaluator
        if getattr(base, "__abstractmethods__", None):  # the ABC of this version
            return type("InstantEvaluator", (Instant, base), {})()
    return Instant()


#: A simulation's record of measures (`SimResult.measures`), for trees that keep it: the stand-in
#: sends one per robot, as a real job does (energy not measured: a speed run).
MEASURES = (
    "distance",
    "speed",
    "forward_speed",
    "climb_rate",
    "heading",
    "energy",
    "cost_of_transport",
    "efficiency",
    "stable",
    "total_mass",
    "masses",
    "springs",
)


def job_output(
    fitness: list[float], form: str | None, record_text: Any = None
) -> dict[str, list[Any]]:
    """The job function's JSON output for these speeds: with each robot's record of measures
    (`form` "measures", this layout) and, where the tree's job sends them, the records' texts
    by its own `record_text`; its heading alone (the release before records), or neither.
    Values made up from the speed, but as many and as varied as a simulation's."""
    output: dict[str, list[Any]] = {"fitness": list(fitness)}
    if form == "heading":
        output["heading"] = [speed * 360.0 - 180.0 for speed in fitness]
    elif form == "measures":
        output["measures"] = [
            {
                name: None if name == "energy" else speed * (1.0 + 0.1 * k)
                for k, name in enumerate(MEASURES)
            }
            for speed in fitness
        ]
        if record_text is not None:
            output["texts"] = [record_text(record) for record in output["measures"]]
    return output


#: CPU seconds the stand-in evaluator spent on its fitness arithmetic (all threads), and its lock.
STAND_IN_CPU = [0.0]
STAND_IN_LOCK = threading.Lock()

#: What each `--algorithms` entry adds to the paper-voxel run.
ALGORITHMS: dict[str, dict[str, Any]] = {
    "ga": {},
    "map-elites": {
        "algorithm": "map-elites",
        "descriptors": ["voxels", "actuated"],
        "bins": [10, 10],
    },
    "nsga2": {"algorithm": "nsga2", "objectives": ["speed", "-cost_of_transport"]},
    "afpo": {"algorithm": "afpo", "objectives": ["speed", "-cost_of_transport"]},
    "steady-state": {"algorithm": "steady-state"},  # per birth: P births make a generation
}

#: `--population` (the paper's 25 unless given), read by `drive` in every fresh interpreter.
POPULATION = int(os.environ.get("SOFTEVO_BENCH_POPULATION", "25"))


def drive(
    found: dict[str, Any], url: str, generations: int, sim_seconds: float, algorithm: str = "ga"
) -> tuple[float, float, int, int]:
    """One run to completion: (CPU seconds of this process less the stand-in evaluator's fitness
    arithmetic, wall seconds, individuals, robots simulated)."""
    database = found["db"].Database(url)
    database.upgrade()
    request = {
        "preset": "paper-voxel",
        "seed": 1,
        "generations": generations,
        "population": POPULATION,
    }
    config = found["resolve"]({**request, **ALGORITHMS[algorithm]})
    run = found["create_run"](database, config)
    coordinator = found["Coordinator"](
        database, instant_evaluator(found, sim_seconds), batch_size=4
    )
    STAND_IN_CPU[0] = 0.0
    cpu, wall = time.process_time(), time.perf_counter()
    coordinator.start()
    gc.freeze()  # as the service does once the coordinator has started (`api.app`, both trees)
    if hasattr(coordinator, "join"):  # wait on the driver thread: no polling in the measurement
        active = ("queued", "running")
        while (
            run.id not in coordinator.active and found["get_run"](database, run.id).status in active
        ):
            coordinator.wait_ticks(1, timeout=60)
        coordinator.join(run.id, timeout=3600)
    while found["get_run"](database, run.id).status in ("queued", "running"):
        time.sleep(0.2)  # rarely (old trees): this process's CPU is what is measured
    cpu, wall = time.process_time() - cpu - STAND_IN_CPU[0], time.perf_counter() - wall
    coordinator.stop()
    record = found["get_run"](database, run.id)
    status, simulated = record.status, getattr(record, "evaluations", 0)
    database.dispose()
    if status != "completed":
        raise SystemExit(f"run ended {status}")
    return cpu, wall, config.population * generations, simulated


def measure_once(
    tree: str | None, database: str, generations: int, sim_seconds: float, algorithm: str
) -> None:
    """One run in this process (of this checkout, or of `tree` when it is on the path); prints
    its CPU seconds, wall seconds and individuals as JSON."""
    if tree is not None:  # its own strategies, not the installed checkout's
        from staged import own_strategies

        own_strategies(Path(tree))
    found = modules(tree)
    with tempfile.TemporaryDirectory() as folder:  # warm up: a long-lived service pays imports
        drive(found, f"sqlite:///{Path(folder) / 'warm.db'}", 3, 0.0, algorithm)  # and first calls
    if database == "sqlite":
        with tempfile.TemporaryDirectory() as folder:
            url = f"sqlite:///{Path(folder) / 'b.db'}"
            row = drive(found, url, generations, sim_seconds, algorithm)
    else:
        with found["db"].scratch_postgres(POSTGRES, "softevo_bench") as url:
            row = drive(found, url, generations, sim_seconds, algorithm)
    print(json.dumps(row))


def stage(tree: str) -> str:
    """A folder where `import softevo.api` finds `tree`'s code: the tree as installed, or the
    tree itself when it is of the old layout (top-level `core` and `api`)."""
    if (Path(tree) / "api" / "storage.py").exists():
        return tree
    from staged import stage as staged

    return str(staged(Path(tree)))


def run_once(
    label: str, path: str | None, database: str, args: argparse.Namespace, algorithm: str = "ga"
) -> tuple[float, float, int, int]:
    """One run in a fresh interpreter (so neither tree's imports or caches help the other)."""
    command = [
        sys.executable,
        "-P",
        __file__,
        "--once",
        database,
        "--generations",
        str(args.generations),
        "--sim-seconds",
        str(args.sim_seconds),
        "--algorithms",
        algorithm,
    ]
    env = dict(os.environ)
    if path is not None:
        command += ["--tree", path]
        env["PYTHONPATH"] = path
    out = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise SystemExit(f"{label} on {database} failed:\n{out.stderr[-3000:]}")
    cpu, wall, individuals, simulated = json.loads(out.stdout.strip().splitlines()[-1])
    return cpu, wall, individuals, simulated


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--generations", type=int, default=60)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--sim-seconds",
        type=float,
        default=0.05,
        help="simulated seconds of wall time per robot (slept, no CPU; 0: instant)",
    )
    parser.add_argument("--tree", help="also measure the checkout at this path, interleaved")
    parser.add_argument(
        "--algorithms",
        default="ga",
        help="comma-separated: ga (default), map-elites, nsga2, afpo, steady-state",
    )
    parser.add_argument(
        "--population", type=int, help="individuals per generation (25, the paper's)"
    )
    parser.add_argument("--once", choices=["sqlite", "postgres"], help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.population:  # the fresh interpreters of each run read it from the environment
        os.environ["SOFTEVO_BENCH_POPULATION"] = str(args.population)
    algorithms = args.algorithms.split(",")
    if args.once:
        measure_once(args.tree, args.once, args.generations, args.sim_seconds, algorithms[0])
        return
    if len(algorithms) > 1:
        compare_algorithms(args, algorithms)
        return
    trees: list[tuple[str, str | None]] = [("this checkout", None)]
    if args.tree:
        staged = stage(args.tree)
        if staged != args.tree:
            atexit.register(shutil.rmtree, staged, True)
        trees.insert(0, (args.tree, staged))
    print(
        f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, {args.generations} generations of "
        f"{args.population or 25}, "
        f"{args.sim_seconds:g} s per robot, median of {args.repeats} (trees interleaved), "
        f"{algorithms[0]}"
    )
    print("database  tree                CPU/individual  wall/generation  generations/s")
    for database in ("sqlite", "postgres"):
        rows: dict[str, list[tuple[float, float, int, int]]] = {label: [] for label, _ in trees}
        for _ in range(args.repeats):
            for label, path in trees:
                rows[label].append(run_once(label, path, database, args, algorithms[0]))
        cpu_of = {}
        for label, _ in trees:
            cpu = statistics.median(c / n for c, _, n, _ in rows[label]) * 1e3
            wall = statistics.median(w / args.generations for _, w, _, _ in rows[label])
            cpu_of[label] = cpu
            print(
                f"{database:9} {label[-18:]:18} {cpu:11.3f} ms  {wall * 1e3:12.2f} ms  "
                f"{1 / wall:12.1f}"
            )
        if len(trees) == 2:
            ratio = cpu_of[trees[0][0]] / cpu_of["this checkout"]
            print(f"{database:9} this checkout: {ratio:.2f}x less CPU per individual")


def compare_algorithms(args: argparse.Namespace, algorithms: list[str]) -> None:
    """This checkout's CPU per individual for each algorithm, runs interleaved, and each
    against the first's."""
    print(
        f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, {args.generations} generations of "
        f"{args.population or 25}, "
        f"{args.sim_seconds:g} s per robot, median of {args.repeats} (algorithms interleaved)"
    )
    print(
        "database  algorithm           CPU/individual  / first's  simulated  CPU/simulation"
        "  / first's"
    )
    for database in ("sqlite", "postgres"):
        rows: dict[str, list[tuple[float, float, int, int]]] = {name: [] for name in algorithms}
        for _ in range(args.repeats):
            for name in algorithms:
                rows[name].append(run_once(name, None, database, args, name))
        per = {  # CPU per individual and per simulated robot (ms), simulations
            name: (
                statistics.median(c / n for c, _, n, _ in rows[name]) * 1e3,
                statistics.median(c / max(1, e) for c, _, _, e in rows[name]) * 1e3,
                statistics.median(e for *_, e in rows[name]),
            )
            for name in algorithms
        }
        first = per[algorithms[0]]
        for name, (cpu, per_sim, simulated) in per.items():
            print(
                f"{database:9} {name:18} {cpu:11.3f} ms  {cpu / first[0]:8.2f}  {simulated:9.0f}"
                f"  {per_sim:11.3f} ms  {per_sim / first[1]:8.2f}"
            )


if __name__ == "__main__":
    main()
