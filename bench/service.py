"""Service throughput benchmark: `python bench/service.py [--repeats R] [--worker-class fork]`.

Runs the same `paper-voxel` experiment (4x4x4, seed 1, population 25, 100 generations by
default) on each of these paths and prints evaluations per second for each:

* `service + RQ`: `softevo serve` in a subprocess with SOFTEVO_REDIS_URL pointing at a private
  redis-server (free port, no persistence) and 2 `softevo worker` subprocesses; once with RQ's
  forking `Worker` (the default) and once with `SimpleWorker` (`--worker-class fork,simple`, the
  default; each class has its own redis-server);
* `service, local pool`: `softevo serve` without Redis, SOFTEVO_WORKERS=2 (its in-process pool);
* `Evolution + PoolEvaluator(2)`: plain `core.evolution.Evolution` in this process.

Every path is started once and kept warm; the timed runs then go round the paths `--repeats`
times (3), and each path's median run stands for it, so a slow spell of a shared machine does not
land on one path only. The service paths use a fresh SQLite file each, create each run with
`POST /runs` and are timed from the POST to the run's `completed` status by the server's own
clock (the run's `created_at` and `finished_at`; the script polls once a second); evaluations
come from `GET /runs/{id}` (`progress.evaluations`). Before the timed runs each service completes
a small untimed run, so its workers or pool processes are started and warm (RQ workers warm
themselves before they register).

The script prints the ratio of the distributed path to the in-process ones (target >= 0.90) and
where the rest of the time went, from the run's own records: worker-side compute per robot
(`eval_seconds` of `GET /runs/{id}/individuals`; on the local pool it is the pool call's wall
time) and each generation's wall time (`generations.seconds`, read from the SQLite file). Each
generation's batches (the new genomes in index order, cut as the coordinator cuts them: at most
SOFTEVO_BATCH_SIZE each, at least one per worker) are placed on
the 2 workers as they free up, with no overhead at all: what that leaves idle is the generation
barrier's cost; the rest of the wall time is per-batch overhead (queue, database writes, the GA)
and time outside generations (scheduling, commits, polling).

Every run's learning curve must equal plain Evolution's to the last digit (asserted). Every
process started here is stopped at the end.
"""

from __future__ import annotations

import argparse
import contextlib
import heapq
import math
import os
import platform
import signal
import sqlite3
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from typing import Any

import httpx
import rq
from benchlib import OtherLoad, cpu_model, free_port, redis_version
from rq import Worker

from softevo.api.settings import Settings
from softevo.core.config import resolve
from softevo.core.evaluator import split_evenly
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import PoolEvaluator
from softevo.core.robots.robot import VoxelRobot
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.robots.settings import sim_settings
from softevo.core.search.stats import CURVE_COLUMNS
from softevo.local_service import start_service
from softevo.worker.queue import connect

WORKERS = 2
WARM_UP_RUN = {"preset": "quick", "seed": 99, "population": 8, "generations": 1}


def clean_env(**settings: str) -> dict[str, str]:
    """This environment without any SOFTEVO_* setting of the shell, plus `settings`."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("SOFTEVO_")}
    return {**env, **{f"SOFTEVO_{k.upper()}": v for k, v in settings.items()}}


def stop(process: subprocess.Popen, grace: float = 30) -> None:
    """SIGTERM (graceful: uvicorn hands back its runs, RQ finishes its job), then SIGKILL to the
    process group it was started in (pool processes, work horses)."""
    if process.poll() is None:
        process.terminate()
        with contextlib.suppress(subprocess.TimeoutExpired):
            process.wait(grace)
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGKILL)
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.wait(10)


class Processes:
    """Subprocesses, each in its own session, logged to files; all stopped by `stop_all`."""

    def __init__(self, workdir: Path) -> None:
        self.workdir = workdir
        self.running: list[tuple[str, subprocess.Popen]] = []

    def start(self, name: str, command: list[str], env: dict[str, str]) -> subprocess.Popen:
        with (self.workdir / f"{name}.log").open("w") as log:
            process = subprocess.Popen(
                command,
                cwd=self.workdir,
                env=env,
                stdout=log,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        self.running.append((name, process))
        return process

    def check(self) -> None:
        for name, process in self.running:
            if process.poll() is not None:
                log = (self.workdir / f"{name}.log").read_text(errors="replace")[-3000:]
                raise RuntimeError(f"{name} exited ({process.returncode}):\n{log}")

    def stop_all(self) -> None:
        # servers first (they hand their runs back), then workers, then Redis
        for _name, process in reversed(self.running):
            stop(process)
        self.running = []


def start_redis(processes: Processes, name: str) -> str:
    """A private redis-server on a free port (no persistence): its URL."""
    port = free_port()
    command = ["redis-server", "--port", str(port), "--bind", "127.0.0.1"]
    command += ["--save", "", "--appendonly", "no", "--dir", str(processes.workdir)]
    processes.start(name, command, dict(os.environ))
    url = f"redis://127.0.0.1:{port}/0"
    deadline = time.monotonic() + 10
    while True:
        try:
            connect(url).ping()
            return url
        except Exception:
            processes.check()
            if time.monotonic() > deadline:
                raise RuntimeError(f"redis-server did not start on port {port}") from None
            time.sleep(0.05)


def start_workers(processes: Processes, url: str, worker_class: str) -> None:
    for i in range(WORKERS):
        name = f"worker-{worker_class}-{i + 1}"
        command = [sys.executable, "-P", "-m", "softevo.cli", "worker", "--url", url]
        command += ["--worker-class", worker_class, "--name", name, "--log-level", "warning"]
        processes.start(name, command, clean_env())
    connection = connect(url)
    deadline = time.monotonic() + 120
    while Worker.count(connection=connection) < WORKERS:  # registered = kernels warm
        processes.check()
        if time.monotonic() > deadline:
            raise RuntimeError(f"{WORKERS} workers not registered in 120 s")
        time.sleep(0.05)
    connection.close()


def serve(processes: Processes, name: str, env: dict[str, str]) -> tuple[str, int]:
    """`softevo serve` on a free port; its base URL once /healthz answers, and its pid."""
    log = processes.workdir / f"{name}.log"
    local = start_service(env, log, "--log-level", "warning", cwd=processes.workdir)
    processes.running.append((name, local.process))
    return local.url, local.process.pid


def run_to_completion(client: httpx.Client, request: dict[str, Any]) -> tuple[int, float, dict]:
    """POST the run and wait for it; (id, seconds from the POST to completed, the run). The time
    is the server's own: the run's `finished_at` - `created_at` (set by the POST), so polling
    slowly (once a second) neither adds to it nor loads the server."""
    created = client.post("/runs", json=request)
    created.raise_for_status()
    run_id = created.json()["id"]
    deadline = time.monotonic() + 1800
    while True:
        run = client.get(f"/runs/{run_id}").json()
        if run["status"] not in ("queued", "running"):
            break
        if time.monotonic() > deadline:
            raise RuntimeError(f"run {run_id} did not finish in 1800 s: {run['progress']}")
        time.sleep(1.0)
    if run["status"] != "completed":
        raise RuntimeError(f"run {run_id} ended {run['status']}: {run['error']}")
    wall = datetime.fromisoformat(run["finished_at"]) - datetime.fromisoformat(run["created_at"])
    return run_id, wall.total_seconds(), run


def cpu_seconds(pid: int | None) -> float:
    """User + system CPU time of one process so far (its own, not its children's)."""
    if pid is None:
        return 0.0
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def redis_cpu(url: str | None) -> float:
    """CPU seconds (user + system) redis-server has used so far (INFO cpu, microseconds)."""
    if url is None:
        return 0.0
    connection = connect(url)
    try:
        info = connection.info("cpu")
        return float(info["used_cpu_user"]) + float(info["used_cpu_sys"])
    finally:
        connection.close()


def redis_calls(url: str | None, reset: bool = False) -> int:
    """Commands the Redis at `url` has run since the last reset (INFO commandstats)."""
    if url is None:
        return 0
    connection = connect(url)
    try:
        if reset:
            connection.config_resetstat()
            return 0
        stats = connection.info("commandstats")
        return sum(int(v["calls"]) for k, v in stats.items() if k != "cmdstat_info")
    finally:
        connection.close()


def normalised(rows: list[dict[str, Any]]) -> list[tuple]:
    """Curve rows as tuples of CURVE_COLUMNS, NaN written as None (as the API does)."""
    return [
        tuple(
            None if isinstance(row[c], float) and math.isnan(row[c]) else row[c]
            for c in CURVE_COLUMNS
        )
        for row in rows
    ]


def makespan(tasks: list[float], workers: int) -> float:
    """Finish time of `tasks` (s) placed in order on the first free of `workers`, no overhead."""
    free = [0.0] * workers
    for task in tasks:
        heapq.heappush(free, heapq.heappop(free) + task)
    return max(free)


@dataclass
class Result:
    name: str
    wall: float
    evaluations: int
    curve: list[tuple]
    compute: float | None = None  # worker-side seconds, all robots
    batches: int = 0
    ideal: float = 0.0  # sum over generations of the no-overhead makespan of their batches
    in_generations: float = 0.0  # sum of the generations' wall times (s)
    api_cpu: float = 0.0  # CPU seconds of the `softevo serve` process during the run
    redis_cpu: float = 0.0  # CPU seconds of redis-server during the run
    redis_calls: int = 0  # Redis commands during the run
    other: float = 0.0  # cores used meanwhile by processes outside this benchmark
    notes: list[str] = field(default_factory=list)

    @property
    def rate(self) -> float:
        return self.evaluations / self.wall


class ServicePath:
    """`softevo serve` with this environment, warm: it has completed a small run."""

    def __init__(
        self,
        processes: Processes,
        name: str,
        env: dict[str, str],
        database: Path,
        request: dict[str, Any],
        batch_size: int,
        redis: str | None = None,
    ) -> None:
        self.name, self.database, self.request = name, database, request
        self.batch_size = batch_size
        self.redis_url = redis
        base, self.pid = serve(processes, name, env)
        self.client = httpx.Client(base_url=base, timeout=60)
        run_to_completion(self.client, WARM_UP_RUN)  # untimed: workers / pool processes warm

    def close(self) -> None:
        self.client.close()

    def run(self) -> Result:
        redis_calls(self.redis_url, reset=True)
        api_cpu, redis = cpu_seconds(self.pid), redis_cpu(self.redis_url)
        other = OtherLoad().start()
        run_id, wall, run = run_to_completion(self.client, self.request)
        other_load = other.stop()
        api_cpu = cpu_seconds(self.pid) - api_cpu
        redis = redis_cpu(self.redis_url) - redis
        calls = redis_calls(self.redis_url)
        curve = self.client.get(f"/runs/{run_id}/curve").json()["generations"]
        items, offset = [], 0
        while True:
            page = self.client.get(
                f"/runs/{run_id}/individuals", params={"offset": offset, "limit": 5000}
            ).json()
            items += page["items"]
            offset += len(page["items"])
            if offset >= page["total"] or not page["items"]:
                break
        with contextlib.closing(sqlite3.connect(f"file:{self.database}?mode=ro", uri=True)) as db:
            query = "SELECT generation, seconds FROM generations WHERE run_id = ?"
            seconds = dict(db.execute(query, (run_id,)))
        # The batches the coordinator sent: each generation's new genomes in index order, cut by
        # split_evenly; an individual's eval_seconds is its batch's worker-side time / its length.
        evaluated: dict[int, list[dict]] = defaultdict(list)
        for item in items:
            if item["status"] in ("evaluated", "failed"):
                evaluated[item["generation"]].append(item)
        compute, batches, ideal = 0.0, 0, 0.0
        workers_seen = set()
        for generation_items in evaluated.values():
            generation_items.sort(key=lambda item: item["index"])
            tasks = []
            for batch in split_evenly(range(len(generation_items)), self.batch_size, WORKERS):
                members = [generation_items[i] for i in batch]
                tasks.append(sum(item["eval_seconds"] for item in members))
                workers_seen.update(item["worker"] for item in members)
            compute += sum(tasks)
            batches += len(tasks)
            ideal += makespan(tasks, WORKERS)
        result = Result(
            self.name,
            wall,
            run["progress"]["evaluations"],
            normalised(curve),
            compute=compute,
            batches=batches,
            ideal=ideal,
            in_generations=sum(seconds.values()),
            api_cpu=api_cpu,
            redis_cpu=redis,
            redis_calls=calls,
            other=other_load,
        )
        result.notes.append(f"worker names: {', '.join(sorted(w for w in workers_seen if w))}")
        return result


class EvolutionPath:
    """Plain `Evolution` in this process with a warm `PoolEvaluator(2)`."""

    name = "Evolution + PoolEvaluator(2)"

    def __init__(self, request: dict[str, Any]) -> None:
        self.config = resolve(request)
        self.pool = PoolEvaluator(WORKERS)
        tiny = robot_to_json(
            VoxelRobot((1, 1, 1), ("hard",), sim=sim_settings({"duration": 0.01, "settle_time": 0}))
        )
        # untimed: both pool processes started and warm
        with ThreadPoolExecutor(4) as hands:
            list(hands.map(lambda i: self.pool.evaluate_batch([tiny], f"warm-{i}"), range(4)))

    def close(self) -> None:
        self.pool.close()

    def run(self) -> Result:
        evolution = Evolution.start(self.config)
        other = OtherLoad().start()
        started = time.perf_counter()
        evolution.run(self.pool)
        wall = time.perf_counter() - started
        curve = normalised(evolution.curve())
        return Result(self.name, wall, evolution.evaluations, curve, other=other.stop())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--generations", type=int, default=100, help="generations (100)")
    parser.add_argument("--population", type=int, default=25, help="population (25)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--sim-duration",
        type=float,
        help="simulated seconds per robot (default: the preset's 10 s); a short one shows how "
        "fast the service itself can go",
    )
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per path, median (3)")
    parser.add_argument(
        "--worker-class",
        default="fork,simple",
        help="RQ worker class(es) for the distributed path: fork, simple or fork,simple (both)",
    )
    parser.add_argument(
        "--batch-size", type=int, help="SOFTEVO_BATCH_SIZE for both services (the default)"
    )
    args = parser.parse_args()
    request = {
        "preset": "paper-voxel",
        "seed": args.seed,
        "shape": [4, 4, 4],
        "population": args.population,
        "generations": args.generations,
    }
    if args.sim_duration is not None:  # short simulations: what the service itself can drive
        request["sim"] = {"duration": args.sim_duration, "settle_time": args.sim_duration / 4}
    settings = (
        clean_env() if args.batch_size is None else clean_env(batch_size=str(args.batch_size))
    )
    batch_size = Settings.from_env(settings).batch_size

    print(
        f"machine: {os.cpu_count()} cores, {cpu_model()}, load {os.getloadavg()[0]:.2f}, "
        f"Python {platform.python_version()}, rq {rq.__version__}, "
        f"redis-server {redis_version()}"
    )
    simulated = "10 s" if args.sim_duration is None else f"{args.sim_duration} s"
    print(
        f"run: paper-voxel 4x4x4, seed {args.seed}, population {args.population}, "
        f"{args.generations} generations, {simulated} simulated; {WORKERS} workers on every "
        f"path; SOFTEVO_BATCH_SIZE {batch_size}; SQLite\n"
    )

    runs: dict[str, list[Result]] = defaultdict(list)
    paths: list[ServicePath | EvolutionPath] = []
    with tempfile.TemporaryDirectory(prefix="softevo-bench-service-") as tmp:
        workdir = Path(tmp)
        processes = Processes(workdir)
        try:
            # Every path is started once and kept warm; the timed runs go round them in turn,
            # so a slow spell of a shared machine does not land on one path only.
            for worker_class in args.worker_class.split(","):
                url = start_redis(processes, f"redis-{worker_class}")
                start_workers(processes, url, worker_class)
                database = workdir / f"rq-{worker_class}.db"
                env = {
                    **settings,
                    "SOFTEVO_DATABASE_URL": f"sqlite:///{database}",
                    "SOFTEVO_REDIS_URL": url,
                }
                name = f"service + RQ ({worker_class})"
                paths.append(ServicePath(processes, name, env, database, request, batch_size, url))
            database = workdir / "local.db"
            env = {
                **settings,
                "SOFTEVO_DATABASE_URL": f"sqlite:///{database}",
                "SOFTEVO_WORKERS": str(WORKERS),
            }
            name = "service, local pool"
            paths.append(ServicePath(processes, name, env, database, request, batch_size))
            paths.append(EvolutionPath(request))
            for round_number in range(1, args.repeats + 1):
                for path in paths:
                    result = path.run()
                    runs[path.name].append(result)
                    print(
                        f"  round {round_number}  {path.name:<30}{result.wall:7.2f} s"
                        f"{result.rate:8.2f} eval/s   other load {result.other:.2f} cores",
                        flush=True,
                    )
        finally:
            for path in paths:
                path.close()
            processes.stop_all()

    # each path's median run (by wall time) stands for it
    results = [sorted(runs[p.name], key=lambda r: r.wall)[(args.repeats - 1) // 2] for p in paths]
    spread = {name: (min(r.rate for r in rs), max(r.rate for r in rs)) for name, rs in runs.items()}
    print(f"\nmedian of {args.repeats} runs per path")
    print(
        f"{'path':<30}{'wall (s)':>9}{'evaluations':>12}{'eval/s':>8}{'min-max eval/s':>16}"
        f"{'generations/s':>15}"
    )
    for r in results:
        low, high = spread[r.name]
        print(
            f"{r.name:<30}{r.wall:>9.2f}{r.evaluations:>12}{r.rate:>8.2f}"
            f"{f'{low:.2f}-{high:.2f}':>16}{args.generations / r.wall:>15.2f}"
        )
    every = [r for rs in runs.values() for r in rs]
    print(
        f"other load: CPU of processes outside this benchmark, the most during any timed run: "
        f"{max(r.other for r in every):.2f} cores (a quiet machine reads 0.0x)"
    )

    local = next(r for r in results if r.name == "service, local pool")
    plain = results[-1]
    print("\nratio distributed / in-process (target >= 0.90)")
    for r in results:
        if r.name.startswith("service + RQ"):
            print(
                f"  {r.name}: {r.rate / local.rate:.3f} of the service's local pool, "
                f"{r.rate / plain.rate:.3f} of plain Evolution"
            )
    print(f"  service, local pool: {local.rate / plain.rate:.3f} of plain Evolution")

    print(
        f"\nwhere the service's time went ({WORKERS} workers, batches of {batch_size}; "
        "worker time per batch, ms)"
    )
    print(
        f"{'path':<30}{'batches':>8}{'compute/robot':>14}{'busy':>7}{'idle':>7}"
        f"{'= barrier':>10}{'+ overhead':>11}{'+ outside':>10}"
    )
    for r in results:
        if r.compute is None:
            continue
        per_batch = 1000 * WORKERS / r.batches
        idle = (WORKERS * r.wall - r.compute) / r.batches * 1000
        barrier = (WORKERS * r.ideal - r.compute) / r.batches * 1000
        overhead = (r.in_generations - r.ideal) * per_batch
        outside = (r.wall - r.in_generations) * per_batch
        print(
            f"{r.name:<30}{r.batches:>8}{1000 * r.compute / r.evaluations:>11.1f} ms"
            f"{r.compute / (WORKERS * r.wall):>7.1%}{idle:>7.1f}{barrier:>10.1f}"
            f"{overhead:>11.1f}{outside:>10.1f}"
        )
    print(
        "  busy = compute / (workers x wall); idle = (workers x wall - compute) / batches; barrier:"
    )
    print(
        "  idle even with no overhead at all (a generation's last batches leave a worker waiting);"
    )
    print("  overhead: the generations' wall time beyond that; outside: time between generations")
    print("  (the POST, scheduling, each generation's commit)")

    generations = args.generations
    print("\ncost of the service itself, per batch and per generation (CPU of one process, ms)")
    print(
        f"{'path':<30}{'API CPU/batch':>14}{'/generation':>12}{'API busy':>9}"
        f"{'Redis CPU/batch':>16}{'Redis cmds/batch':>17}"
    )
    for r in results:
        if r.compute is None:
            continue
        redis = f"{1000 * r.redis_cpu / r.batches:.2f}" if r.redis_calls else "-"
        calls = f"{r.redis_calls / r.batches:.1f}" if r.redis_calls else "-"
        print(
            f"{r.name:<30}{1000 * r.api_cpu / r.batches:>14.2f}"
            f"{1000 * r.api_cpu / generations:>12.2f}{r.api_cpu / r.wall:>9.1%}"
            f"{redis:>16}{calls:>17}"
        )
    print("  API CPU: the `softevo serve` process itself (coordinator, database, enqueueing and,")
    print("  on the local pool, feeding its pool; not the pool processes), polled once a second")
    for r in results:
        for note in r.notes:
            print(f"  {r.name}: {note}")

    reference = plain.curve
    for r in every:
        assert r.evaluations == plain.evaluations, (r.name, r.evaluations, plain.evaluations)
        assert r.curve == reference, f"{r.name}: curve differs from plain Evolution"
    last = dict(zip(CURVE_COLUMNS, reference[-1], strict=True))
    print(
        f"\nsame curve on every path, to the last digit: {len(reference)} generations, "
        f"{plain.evaluations} evaluations, best so far {last['best_so_far']!r} m/s"
    )
    fresh = Counter(row[CURVE_COLUMNS.index("evaluations")] for row in reference[1:])
    print(
        "new genomes per generation after the first (new genomes: generations): "
        + ", ".join(f"{n}: {count}" for n, count in sorted(fresh.items()))
    )


if __name__ == "__main__":
    main()
