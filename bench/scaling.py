"""Past one machine, by simulation (issue 37): `nice -n 5 python bench/scaling.py [--workers 32]
[--population 200] [--generations 30] [--windows 128,200] [--algorithms steady-state,ga]
[--database sqlite|postgres] [--robot-ms MS1,MS2,MS3,MS4] [--profile] [--tree PATH]`.

One API process (this one: the service's `Coordinator` on a fresh SQLite database, or a scratch
PostgreSQL one, its evaluator the service's `RQEvaluator`) drives a `paper-voxel` run (4x4x4,
seed 1) of `population` x `generations` at a time, on `workers` RQ `SimpleWorker` processes and
a private redis-server on this machine. The workers are built as `softevo worker --worker-class
simple` builds them (softevo's job class, queue and JSON serializer; no kernels loaded) and run
the stand-in job `bench/scaling_job.py`: it sleeps each batch's simulation time by a time model
measured here first (each robot's seconds per occupied voxel in a kernel call of 1, 2, 3 and 4
robots, `evaluate_robot_files`, best of 3; `--robot-ms` gives the ms of the sample's mean robot
instead) and returns a deterministic fitness with a record of measures, so the run is the real
RQ path (enqueue, Redis round trips, results, the store's writes) with only the simulation
replaced, and the workers cost no CPU but RQ's own.

Each steady-state window in `--windows` and the generational GA at the same population are run
once, after an untimed warm-up run. For each it prints: the fraction of worker-time spent busy
(the stand-in's simulation seconds / (workers x wall), the wall from the coordinator's start to
the run's last commit), the same in the middle 80 % of the wall, the share of that middle in
which no job waited on the queue (sampled every 50 ms: a worker that finished a job then waited
for the coordinator) and the median gap between a worker's jobs (RQ's work on both sides of a
job, and any such wait); the coordinator's CPU per birth (this process's CPU over the run: its
step, store and RQ client; the stand-in's arithmetic runs on the workers, so nothing is taken
out), split into the run's driver thread, the batch threads (enqueue, BLPOP, decode, checks) and
the rest; Redis commands (INFO commandstats) and read events (INFO stats `total_reads_processed`,
about one per round trip, a pipeline counting once) per simulated robot; redis-server's and the
workers' CPU per job; and the load of other processes meanwhile (`OtherLoad`). `--profile` runs
each once more under yappi (CPU clock, every thread) and prints where this process's time goes.

`--tree PATH [--repeats N]` compares the API side of an earlier checkout (a `git worktree`):
each run goes to a fresh interpreter of the tree and of this checkout in turn (A B, N times,
after a warm-up run in each), on the same redis-server and workers, and prints this
checkout's API CPU per birth against the tree's (the medians) for each run. A tree whose
pyproject does not ask for hiredis runs without it, as its own locks would have installed it.
"""

from __future__ import annotations

import argparse
import contextlib
import gc
import itertools
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
from collections.abc import Iterator
from dataclasses import asdict
from pathlib import Path
from typing import Any

import rq
import scaling_job
from benchlib import cpu_model, redis_version
from rq import Worker
from rq_workers import redis_server, stop
from scaling_meter import HEADER, Figures, Meter, median_gap, mid_busy, profile
from staged import own_strategies, stage

from softevo.api import store
from softevo.api.coordinator import Coordinator
from softevo.api.db import Database, scratch_postgres
from softevo.core.config import resolve
from softevo.worker.evaluator import RQEvaluator
from softevo.worker.queue import connect

POSTGRES = os.environ.get("SOFTEVO_TEST_POSTGRES", "postgresql://postgres@127.0.0.1:5432/test")
BENCH = Path(__file__).resolve().parent
#: One worker: `softevo worker --worker-class simple`'s worker without the kernels' warm-up.
WORKER = """
import sys
from rq import Queue, SimpleWorker
from softevo.worker.allow_list import job_class
from softevo.worker.queue import QUEUE, SERIALIZER, connect
url, name, function = sys.argv[1:4]
connection = connect(url)
jobs = job_class((function,))
queues = [Queue(QUEUE, connection=connection, serializer=SERIALIZER, job_class=jobs)]
worker = SimpleWorker(queues, connection=connection, serializer=SERIALIZER, job_class=jobs,
                      name=name)
worker.work(logging_level="WARNING", with_scheduler=False)
"""
WIDTHS = (1, 2, 3, 4)


def measure_model(repeats: int = 3, robots: int = 8) -> tuple[dict[int, float], float]:
    """Seconds per occupied voxel in a kernel call of n robots (first-generation paper-voxel
    robots of seed 1, the best of `repeats`), and the sample's mean occupied voxels."""
    from softevo.core.evolution import Evolution
    from softevo.core.physics.evaluation import evaluate_robot_files, warm_up
    from softevo.core.robots.robot_file import robot_to_json

    warm_up()
    run = Evolution.start(resolve({"preset": "paper-voxel", "seed": 1}))
    files = [robot_to_json(run.robot(item)) for item in run.individuals()][:robots]
    voxels = [scaling_job.occupied(f) for f in files]
    per_voxel = {}
    for width in WIDTHS:
        best = float("inf")
        for _ in range(repeats):
            started = time.perf_counter()
            for start in range(0, robots, width):
                evaluate_robot_files(files[start : start + width])
            best = min(best, time.perf_counter() - started)
        per_voxel[width] = best / sum(voxels)
    return per_voxel, sum(voxels) / len(voxels)


class CountedRQ(RQEvaluator):
    """The service's RQ evaluator, adding up what its jobs report: simulation seconds, jobs,
    robots (a few additions per job: no measurable CPU)."""

    def __init__(self, url: str) -> None:
        super().__init__(url, job_function=scaling_job.FUNCTION)
        self.busy, self.jobs, self.robots = 0.0, 0, 0
        self.spans: list[tuple[str, float, float]] = []  # each job's worker, start, seconds
        self._counted = threading.Lock()

    def collect(self, files: list[dict[str, Any]], key: str, *args: Any) -> dict[str, Any]:
        payload = super().collect(files, key, *args)
        if "fitness" in payload:
            with self._counted:
                self.busy += float(payload["seconds"])
                self.jobs += 1
                self.robots += len(files)
                started, seconds = float(payload["started"]), float(payload["seconds"])
                self.spans.append((str(payload["worker"]), started, seconds))
        return payload


@contextlib.contextmanager
def workers(url: str, count: int, workdir: Path, per_voxel: dict[int, float]) -> Iterator[list]:
    """`count` SimpleWorkers running the stand-in job, registered before this yields."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("SOFTEVO_")}
    env[scaling_job.MODEL_ENV] = scaling_job.model_json(per_voxel)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(BENCH), env.get("PYTHONPATH")]))
    processes = []
    try:
        with (workdir / "workers.log").open("w") as log:
            for i in range(count):
                command = [sys.executable, "-c", WORKER, url, f"stand-in-{i + 1}"]
                processes.append(
                    subprocess.Popen(
                        [*command, scaling_job.FUNCTION],
                        stdout=log,
                        stderr=subprocess.STDOUT,
                        env=env,
                        start_new_session=True,
                    )
                )
        connection, deadline = connect(url), time.monotonic() + 180
        while Worker.count(connection=connection) < count:
            if any(p.poll() is not None for p in processes) or time.monotonic() > deadline:
                logs = (workdir / "workers.log").read_text()
                raise RuntimeError(f"workers did not start:\n{logs}")
            time.sleep(0.2)
        connection.close()
        yield processes
    finally:
        for process in processes:
            process.terminate()
        for process in processes:
            stop(process, grace=5)


def request(args: argparse.Namespace, algorithm: str, window: int | None) -> dict[str, Any]:
    extra = {} if window is None else {"options": {"window": window}}
    return {
        "preset": "paper-voxel",
        "seed": 1,
        "population": args.population,
        "generations": args.generations,
        "algorithm": algorithm,
        **extra,
    }


@contextlib.contextmanager
def database(kind: str, folder: Path, name: str) -> Iterator[Database]:
    """A fresh database of `kind` (a file in `folder`, or a scratch PostgreSQL database)."""
    with contextlib.ExitStack() as stack:
        if kind == "sqlite":
            url = f"sqlite:///{folder / f'{name}.db'}"
        else:
            url = stack.enter_context(scratch_postgres(POSTGRES, f"softevo_scaling_{name}"))
        db = Database(url)
        db.upgrade()
        try:
            yield db
        finally:
            db.dispose()


def drive(
    db: Database,
    url: str,
    run_request: dict[str, Any],
    batch_size: int,
    pids: list[int],
    label: str,
) -> Figures:
    """One run to completion through a fresh coordinator, measured (see the module)."""
    config = resolve(run_request)
    run = store.create_run(db, config)
    evaluator = CountedRQ(url)
    coordinator = Coordinator(db, evaluator, max_running=1, batch_size=batch_size)
    meter = Meter(url, pids)
    coordinator.start()
    gc.freeze()  # as the service does once its coordinator has started (`api.app`)
    while run.id not in coordinator.active and store.get_run(db, run.id).status == "queued":
        coordinator.wait_ticks(1, timeout=60)
    coordinator.join(run.id, timeout=3600)
    got = meter.stop()
    coordinator.stop()
    evaluator.close()
    record = store.get_run(db, run.id)
    if record.status != "completed":
        raise SystemExit(f"{label}: the run ended {record.status}: {record.error}")
    spans = evaluator.spans
    return Figures(
        label,
        config.population * config.generations,
        evaluator.robots,
        evaluator.jobs,
        got["wall"],
        evaluator.busy,
        mid_busy(spans, got["low"], got["high"], len(pids)),
        got["empty"],
        median_gap(spans),
        got["cpu"],
        got["driver"],
        got["batches"],
        int(got["commands"]),
        int(got["reads"]),
        got["redis"],
        got["workers"],
        got["other"],
        record.best_fitness,
    )


def arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=32, help="RQ SimpleWorkers (32)")
    parser.add_argument("--population", type=int, default=200, help="population (200)")
    parser.add_argument("--generations", type=int, default=30, help="rows of births (30)")
    parser.add_argument("--windows", default="128,200", help="steady-state windows (128,200)")
    parser.add_argument("--algorithms", default="steady-state,ga", help="steady-state,ga")
    parser.add_argument("--batch-size", type=int, default=4, help="robots per job (4)")
    parser.add_argument("--database", choices=["sqlite", "postgres"], default="sqlite")
    parser.add_argument("--robot-ms", help="ms of the sample's mean robot in a call of 1,2,3,4")
    parser.add_argument("--profile", action="store_true", help="each run again under yappi")
    parser.add_argument("--tree", help="also run an earlier checkout's API side, alternated")
    parser.add_argument("--repeats", type=int, default=1, help="with --tree: A B pairs (1)")
    parser.add_argument("--once", help=argparse.SUPPRESS)  # a --tree child's run, as JSON
    return parser.parse_args()


def print_header(args: argparse.Namespace, per_voxel: dict[int, float], mean: float) -> None:
    load = os.getloadavg()
    print(
        f"# {cpu_model()}, {os.cpu_count()} cores, load {load[0]:.2f} {load[1]:.2f} "
        f"{load[2]:.2f}, Python {platform.python_version()}, rq {rq.__version__}, "
        f"redis-server {redis_version()}, {args.database}"
    )
    print(
        f"# paper-voxel 4x4x4 seed 1, population {args.population} x {args.generations}, "
        f"{args.workers} SimpleWorkers, batches of {args.batch_size}; the stand-in sleeps "
        + ", ".join(f"{1e3 * per_voxel[w] * mean:.1f}" for w in WIDTHS)
        + f" ms per robot of {mean:.1f} voxels in a call of 1, 2, 3, 4 robots"
    )
    print("# busy: simulation / (workers x wall), mid: the same in the wall's middle 80 %;")
    print("# q=0: the share of the middle with no job queued; gap: median ms between a worker's")
    print("# jobs (RQ's work on both sides, the result's push, any wait for a job);")
    print("# CPU/b: this process's CPU per birth (ms), driver and batches: its threads'; cmd/r,")
    print("# rd/r: Redis commands and read events per robot; redis, workers: their CPU per job")
    print("# (ms); other: cores used meanwhile by processes outside this bench")
    print(("tree  " if args.tree else "") + HEADER, flush=True)


def run_child(args: argparse.Namespace) -> None:
    """`--once`: a warm-up run, then the measured one, in this fresh interpreter (of this
    checkout, or of the staged tree first on PYTHONPATH); the figures as JSON."""
    spec = json.loads(args.once)
    if spec["tree"]:
        own_strategies(Path(spec["tree"]))
        if not str(Path(store.__file__).resolve()).startswith(spec["tree"]):
            raise SystemExit(f"imported {store.__file__}, not the tree's")
    folder, figures = Path(spec["folder"]), None
    for part, generations in (("warm", 2), ("run", spec["request"]["generations"])):
        run_request = {**spec["request"], "generations": generations}
        with database(args.database, folder, f"{spec['name']}{part}") as db:
            figures = drive(db, spec["url"], run_request, args.batch_size, spec["pids"], "")
    print(json.dumps(asdict(figures)))


def in_child(args: argparse.Namespace, spec: dict[str, Any], staged: str | None) -> Figures:
    """One run of `--tree`'s alternation, in a fresh interpreter (neither tree's imports help
    the other); `staged` is the earlier tree, or None for this checkout."""
    env = dict(os.environ)
    prelude = ""
    if staged is not None:
        env["PYTHONPATH"] = os.pathsep.join([staged, str(BENCH)])
        if "hiredis" not in (Path(staged) / "pyproject.toml").read_text():
            prelude = "sys.modules['hiredis'] = None; "  # as its locks installed it: without
    options = ["--once", json.dumps({**spec, "tree": staged}), "--database", args.database]
    options += ["--batch-size", str(args.batch_size)]
    script = f"import runpy, sys; {prelude}sys.argv = {[__file__, *options]!r}; "
    command = [sys.executable, "-c", script + f"runpy.run_path({__file__!r}, run_name='__main__')"]
    out = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise SystemExit(f"{spec['name']} failed:\n{out.stderr[-3000:]}")
    return Figures(**json.loads(out.stdout.strip().splitlines()[-1]))


def alternate(
    args: argparse.Namespace, runs: list, url: str, pids: list[int], folder: Path
) -> None:
    """Each run of the earlier tree and of this checkout in turn, `repeats` times; then this
    checkout's CPU per birth against the tree's (the medians)."""
    staged = stage(Path(args.tree))
    trees = [("tree", str(staged)), ("this", None)]
    for number, (label, run_request) in enumerate(runs):
        per_birth: dict[str, list[float]] = {"tree": [], "this": []}
        for repeat, (name, path) in itertools.product(range(args.repeats), trees):
            spec = {"url": url, "pids": pids, "folder": str(folder), "request": run_request}
            got = in_child(args, {**spec, "name": f"{name}{number}r{repeat}"}, path)
            got.label = label
            per_birth[name].append(got.cpu / got.births)
            print(f"{name:<6}" + got.line(args.workers), flush=True)
        ratio = statistics.median(per_birth["tree"]) / statistics.median(per_birth["this"])
        print(f"# {label}: this checkout {ratio:.2f}x less API CPU per birth than the tree")
    shutil.rmtree(staged, ignore_errors=True)


def main() -> None:
    args = arguments()
    if args.once:
        run_child(args)
        return
    if shutil.which("redis-server") is None:
        sys.exit("bench/scaling.py needs the redis-server binary")
    if args.robot_ms:
        per_voxel, mean = measure_model(repeats=1, robots=1)  # only the sample's mean voxels
        ms = [float(v) for v in args.robot_ms.split(",")]
        per_voxel = {width: ms[i] / 1e3 / mean for i, width in enumerate(WIDTHS)}
    else:
        per_voxel, mean = measure_model()
    runs = [
        (f"steady-state W={w}", request(args, "steady-state", int(w)))
        for w in args.windows.split(",")
        if "steady-state" in args.algorithms.split(",")
    ] + [("ga", request(args, "ga", None))] * ("ga" in args.algorithms.split(","))
    print_header(args, per_voxel, mean)
    with tempfile.TemporaryDirectory(prefix="softevo-scaling-") as tmp:
        folder = Path(tmp)
        with redis_server(folder) as url, workers(url, args.workers, folder, per_voxel) as procs:
            pids = [process.pid for process in procs]
            if args.tree:
                alternate(args, runs, url, pids, folder)
            else:
                in_process(args, runs, url, pids, folder)
    load = os.getloadavg()
    print(f"# load after: {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")


def in_process(
    args: argparse.Namespace, runs: list, url: str, pids: list[int], folder: Path
) -> None:
    """Each run in this process, after an untimed warm-up of each; with --profile, again
    under yappi."""

    def once(label: str, run_request: dict[str, Any], name: str) -> Figures:
        with database(args.database, folder, name) as db:
            return drive(db, url, run_request, args.batch_size, pids, label)

    for label, run_request in runs:  # untimed: imports, first calls, every worker
        once(label, {**run_request, "generations": 2}, f"warm{len(label)}")
    for number, (label, run_request) in enumerate(runs):
        print(once(label, run_request, f"run{number}").line(args.workers), flush=True)
    for number, (label, run_request) in enumerate(runs * args.profile):
        profile(lambda: once(label, run_request, f"profile{number}"), label)  # noqa: B023


if __name__ == "__main__":
    main()
