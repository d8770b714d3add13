"""How close evolution runs to the speed of the physics: `python bench/efficiency.py
[--workload paper-voxel,sweep,paper-cube] [--path run,service,service-rq] [--generations G]`.

For each workload and path: the wall time of the work through that path, and the physics bound
for exactly the robots that path simulated (the same robot files, re-simulated here in full SIMD
batches, `simulate_batch(..., threads=cores)`, in this one process), and their ratio bound /
wall (1.0: nothing but simulation). Paths:

* `run`: in process, the library's path (`Evolution` and the local pool on every core; `softevo
  run` drives the same step through its store, 1.04x the wall of a paper-voxel run, BENCHMARKS.md),
  the robots recorded as they are evaluated;
* `service`: a real `softevo serve` on SQLite with its local pool, the run or sweep sent over
  HTTP and timed from the request to its last run completed; the robots read back from the
  database (every individual that was simulated, not those from the cache);
* `service-rq`: the same with a private redis-server and two `softevo worker` processes.

Workloads: `paper-voxel` (4x4x4, seed 1, 25 x G generations, 100 by default), `steady-voxel`
and `steady-cube` (`paper-voxel` and `paper-cube` as `steady-state` runs; `steady-voxel:K`
with a window of K populations), `sweep` (the paper's nine boxes x seeds 1-3 as one `POST /sweeps`,
G generations each; `run` path: the 27 runs one after another), `paper-cube` (the 28-spring cube, 30
x G, 1000 by default), `seeds` (one box, 4x4x4, seeds 1-6 as one sweep, G generations, 40 by
default: runs whose robots can share kernel calls when several are driven at once). Every path warms
its kernels first (a small untimed run), and the bound is measured after the path, in the same
invocation. For one run (not a sweep) it also prints the generation bound: the same robots
cut per generation as the generation step cuts them, each batch timed alone, list-scheduled on
the cores, generations one after another (`generation_bound`): bound / generation bound is the
most any path that keeps the generational semantics can reach, generation bound / wall how much
of that ceiling the path reaches. `--widths [PRESET[:SHAPE]]` prints only the kernel's
per-robot cost against the number of robots in one call (1, 2, 3, 4, 5, 8) and against running
them one by one, and what two calls of two robots cost through the local pool, alone and at once.
`--max-running N` sets the service's SOFTEVO_MAX_RUNNING (runs driven at once).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import platform
import sqlite3
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import httpx
from benchlib import cpu_model
from service import Processes, start_redis, start_workers

from softevo.core.config import RunConfig, resolve
from softevo.core.evaluator import BatchResult, Evaluator, split_evenly
from softevo.core.limits import BATCH_SIZE
from softevo.core.physics import simulate, simulate_batch
from softevo.core.physics.evaluation import PoolEvaluator, evaluate_robot_files
from softevo.core.robots.genome import Genome
from softevo.core.robots.robot_file import parse_robot, robot_to_json
from softevo.core.search.evolution import Evolution
from softevo.local_service import service_env, start_service

BOXES = (
    [3, 3, 6],
    [4, 4, 3],
    [4, 4, 4],
    [5, 5, 3],
    [5, 5, 4],
    [5, 5, 5],
    [6, 6, 3],
    [6, 6, 6],
    [9, 9, 2],
)
SEEDS = (1, 2, 3)


def workload(name: str, generations: int | None) -> list[dict[str, Any]]:
    """The run requests of a workload."""
    if name == "paper-voxel":
        return [{"preset": "paper-voxel", "seed": 1, "generations": generations or 100}]
    if name == "paper-cube":
        return [{"preset": "paper-cube", "seed": 1, "generations": generations or 1000}]
    if name.partition(":")[0] in ("steady-voxel", "steady-cube"):  # steady-state (issue 37)
        name, _, windows = name.partition(":")  # `steady-voxel:2`: a window of 2 populations
        preset = "paper-voxel" if name == "steady-voxel" else "paper-cube"
        request = {**workload(preset, generations)[0], "algorithm": "steady-state"}
        if windows:
            population = resolve({"preset": preset}).population
            request["options"] = {"window": int(windows) * population}
        return [request]
    if name == "seeds":
        return [
            {
                "preset": "paper-voxel",
                "seed": seed,
                "shape": [4, 4, 4],
                "generations": generations or 40,
            }
            for seed in range(1, 7)
        ]
    return [
        {"preset": "paper-voxel", "seed": seed, "shape": box, "generations": generations or 100}
        for box in BOXES
        for seed in SEEDS
    ]


class Recording(Evaluator):
    """The local pool, keeping every robot file it was given, by generation (a batch's key is
    its generation's key, a dash and a digest)."""

    def __init__(self, inner: Evaluator) -> None:
        self.inner = inner
        self.generations: dict[str, list[dict[str, Any]]] = {}
        self._lock = threading.Lock()

    def evaluate_batch(self, robot_files: Any, key: str | None = None) -> BatchResult:
        with self._lock:
            self.generations.setdefault((key or "").rpartition("-")[0], []).extend(robot_files)
        return self.inner.evaluate_batch(robot_files, key)

    def capacity(self) -> int:
        return self.inner.capacity()

    def close(self) -> None:
        self.inner.close()


Files = list[dict[str, Any]]


def through_run(requests: list[dict[str, Any]]) -> tuple[float, list[Files]]:
    """The library's path: each run in this process, one after another, on the local pool."""
    with PoolEvaluator() as pool:
        Evolution.start(resolve({"preset": "quick", "generations": 2})).run(pool)  # warm
        recording = Recording(pool)
        started = time.perf_counter()
        for request in requests:
            Evolution.start(resolve(request)).run(recording)
        return time.perf_counter() - started, list(recording.generations.values())


def simulated_files(database: Path) -> list[Files]:
    """Every robot the service simulated (evaluated or failed, not cached), as robot files, by
    run and generation."""
    with contextlib.closing(sqlite3.connect(database)) as connection:
        rows = connection.execute(
            "SELECT r.config, i.genome, i.run_id, i.generation FROM individuals i "
            "JOIN runs r ON r.id = i.run_id WHERE i.status IN ('evaluated', 'failed') "
            "AND r.id > 1 ORDER BY i.run_id, i.generation, i.id"  # run 1: the warm-up
        ).fetchall()
    generations: dict[tuple[int, int], Files] = {}
    configs: dict[str, RunConfig] = {}
    for config_json, genome_json, run_id, generation in rows:
        config = configs.setdefault(config_json, RunConfig.model_validate(json.loads(config_json)))
        genome = Genome.from_json(json.loads(genome_json))
        robot = config.make_encoding().to_robot(genome, config.sim)
        generations.setdefault((run_id, generation), []).append(robot_to_json(robot))
    return list(generations.values())


@contextlib.contextmanager
def redis_workers(folder: Path) -> Iterator[str]:
    """A private redis-server and two warm `softevo worker` processes: the Redis URL."""
    processes = Processes(folder)
    try:
        url = start_redis(processes, "redis")
        start_workers(processes, url, "fork")
        yield url
    finally:
        processes.stop_all()


def wait_completed(client: httpx.Client, run_ids: list[int]) -> None:
    pending = set(run_ids)
    while pending:
        time.sleep(0.5)
        for run_id in list(pending):
            status = client.get(f"/runs/{run_id}").json()["status"]
            if status == "completed":
                pending.discard(run_id)
            elif status not in ("queued", "running"):
                raise SystemExit(f"run {run_id} ended {status}")


def through_service(
    requests: list[dict[str, Any]], sweep: bool, redis: bool, folder: Path, max_running: int | None
) -> tuple[float, list[Files]]:
    database = folder / "efficiency.db"
    with contextlib.ExitStack() as stack:
        settings = {"database_url": f"sqlite:///{database}"}
        if max_running is not None:
            settings["max_running"] = str(max_running)
        if redis:
            settings["redis_url"] = stack.enter_context(redis_workers(folder))
        local = stack.enter_context(
            start_service(service_env(**settings), folder / "serve.log", "--log-level", "warning")
        )
        client = stack.enter_context(httpx.Client(base_url=local.url, timeout=60))
        warm = client.post("/runs", json={"preset": "quick", "generations": 2}).json()["id"]
        wait_completed(client, [warm])
        started = time.perf_counter()
        if sweep:
            base = {k: v for k, v in requests[0].items() if k not in ("shape", "seed")}
            shapes = list({tuple(r["shape"]): None for r in requests})
            seeds = list({r["seed"]: None for r in requests})
            body = {**base, "shapes": [list(shape) for shape in shapes], "seeds": seeds}
            created = client.post("/sweeps", json=body)
            created.raise_for_status()
            run_ids = [run_id for box in created.json()["boxes"] for run_id in box["run_ids"]]
        else:
            run_ids = [client.post("/runs", json=request).json()["id"] for request in requests]
        wait_completed(client, run_ids)
        wall = time.perf_counter() - started
    return wall, simulated_files(database)


def bound(files: list[dict[str, Any]]) -> float:
    """Seconds to simulate `files` in full SIMD batches on every core, in this process."""
    robots = [parse_robot(file) for file in files]
    simulate_batch(robots[:1])  # kernels loaded
    started = time.perf_counter()
    simulate_batch(robots, threads=os.cpu_count() or 1)
    return time.perf_counter() - started


def generation_bound(generations: list[Files]) -> float:
    """Seconds the generation step's batches would take if nothing but their physics cost
    anything: each generation's new robots cut as the step cuts them (`split_evenly`: batches
    of at most BATCH_SIZE, at least one per core), each batch timed alone on one thread as the
    job function runs it (`small_alone`), the batches of a generation handed in order to the
    first free core, one generation after another. That is the best any path can do that waits
    for each generation's last robot before breeding the next (it leaves out parsing, the pool
    and the coordinator, and two cores slowing each other): bound / this is the ceiling the
    generation barrier leaves, and this / wall how much of that ceiling the path reaches."""
    cores = os.cpu_count() or 1
    robots = [[parse_robot(file) for file in files] for files in generations]
    simulate_batch(robots[0][:1])
    total = 0.0
    for members in robots:
        free = [0.0] * cores  # when each core is next free
        for chunk in split_evenly(range(len(members)), BATCH_SIZE, cores):
            started = time.perf_counter()
            simulate_batch([members[i] for i in chunk], small_alone=True)
            core = free.index(min(free))
            free[core] += time.perf_counter() - started
        total += max(free)
    return total


def widths(robot: str, repeats: int = 3) -> None:
    """Per-robot cost of one kernel call against its width, and of the same robots one at a time
    in `simulate_one` (robots of a run's first generation, one thread; `robot` is a preset, or
    PRESET:SHAPE such as paper-voxel:2x2x2): what a generation of a few new robots pays per
    robot, and where `simulate_batch(small_alone=True)` should switch."""
    preset, _, shape = robot.partition(":")
    request: dict[str, Any] = {"preset": preset, "seed": 1}
    if shape:
        request["shape"] = [int(side) for side in shape.split("x")]
    evolution = Evolution.start(resolve(request))
    robots = [evolution.robot(item) for item in evolution.individuals()[:8]]
    # before this process runs a kernel, so no thread of its own competes with the pool
    pool_line = round_trip([robot_to_json(r) for r in robots[:4]], repeats * 20)
    simulate_batch(robots[:1])
    simulate(robots[0], energy=False)

    def best(run: Callable[[], object], count: int) -> float:
        times = []
        for _ in range(repeats):
            started = time.perf_counter()
            run()
            times.append((time.perf_counter() - started) / count)
        return min(times)

    batched = {w: best(lambda w=w: simulate_batch(robots[:w]), w) for w in (8, 1, 2, 3, 4, 5)}
    alone = best(lambda: [simulate(r, energy=False) for r in robots[:4]], 4)
    print(f"# {robot}: robot by robot (simulate_one) {alone * 1e3:.2f} ms per robot")
    print("robots in one call   ms per robot   against 8 at once   against one by one")
    for width in (1, 2, 3, 4, 5, 8):
        per = batched[width]
        print(f"{width:17d} {per * 1e3:14.2f} {per / batched[8]:19.2f} {per / alone:20.2f}")
    print(pool_line)


def round_trip(files: Files, count: int) -> str:
    """What a generation of four new robots costs on the local pool, cut as the step cuts it
    (two calls of two robots, one a process): one call in this process (`evaluate_robot_files`),
    one through the pool alone (adds the round trip), both calls through the pool at once (adds
    the two cores slowing each other: the physics floor of such a generation)."""
    halves = [files[:2], files[2:4]]

    def timed(run: Callable[[], object]) -> float:
        started = time.perf_counter()
        for _ in range(count):
            run()
        return (time.perf_counter() - started) / count * 1e3

    with PoolEvaluator() as pool, ThreadPoolExecutor(2) as threads:
        for half in halves * 2:
            pool.evaluate_batch(half)  # every process warm
        alone = timed(lambda: pool.evaluate_batch(halves[0]))
        both = timed(lambda: list(threads.map(pool.evaluate_batch, halves)))
    here = timed(lambda: evaluate_robot_files(halves[0]))
    return (
        f"# two robots a call: {here:.2f} ms in this process, {alone:.2f} ms through the "
        f"pool alone, {both:.2f} ms for two such calls through the pool at once"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workload", default="paper-voxel,sweep,paper-cube")
    parser.add_argument("--path", default="run,service,service-rq")
    parser.add_argument("--generations", type=int, help="generations of every run")
    parser.add_argument("--max-running", type=int, help="the service's SOFTEVO_MAX_RUNNING")
    parser.add_argument(
        "--no-bound", action="store_true", help="wall times only (to compare two trees)"
    )
    parser.add_argument(
        "--widths",
        metavar="ROBOT",
        nargs="?",
        const="paper-voxel",
        help="only the kernel's per-robot cost by call width, for PRESET[:SHAPE] robots",
    )
    args = parser.parse_args()
    if args.widths:
        widths(args.widths)
        return
    print(
        f"# {cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
        f"SOFTEVO_MAX_RUNNING {args.max_running or 'default'}"
    )
    print(
        "workload       path         simulations    wall (s)   bound (s)   bound/wall"
        "   generation bound (s)   bound/generation bound   generation bound/wall"
    )
    for name in args.workload.split(","):
        requests = workload(name, args.generations)
        for path in args.path.split(","):
            with tempfile.TemporaryDirectory() as folder:
                if path == "run":
                    wall, generations = through_run(requests)
                else:
                    wall, generations = through_service(
                        requests,
                        name in ("sweep", "seeds"),
                        path == "service-rq",
                        Path(folder),
                        args.max_running,
                    )
            files = [file for members in generations for file in members]
            physics = math.nan if args.no_bound else bound(files)
            # one run at a time: several runs' generations overlap, so theirs add up to no bound
            barrier = (  # (a steady-state run has no generation barrier)
                math.nan
                if args.no_bound or len(requests) > 1 or name.startswith("steady")
                else generation_bound(generations)
            )
            print(
                f"{name:14} {path:12} {len(files):11d} {wall:11.1f} {physics:11.1f} "
                f"{physics / wall:12.2f} {barrier:22.1f} {physics / barrier:24.2f} "
                f"{barrier / wall:23.2f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
