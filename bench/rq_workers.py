"""RQ worker benchmark: `python bench/rq_workers.py [--quick] [--robots N] [--repeats R]`.

Starts a private redis-server on a free port and, one kind at a time, the workers that evaluate
robots for the service, then drives them from this process through `worker.evaluator.RQEvaluator`
(up to 64 batches in flight, as the service does):

* `fork`: `softevo worker --worker-class fork`, RQ's forking `Worker` (the default): a warm parent
  forks a work horse per job and can kill it at job_timeout + 60 s;
* `simple`: `softevo worker --worker-class simple`, RQ's `SimpleWorker`: the job runs in the warm
  worker itself, no fork;
* `pool/simple` and `pool/fork`: RQ's `rq.worker_pool.WorkerPool` in one process that loads the
  kernels first (`softevo.core.physics.evaluation.warm_up`) and then forks its N workers
  (`SimpleWorker`s or forking `Worker`s), so they start warm;
* `PoolEvaluator`: the in-process baseline, `softevo.core.physics.evaluation.PoolEvaluator(n)`
  with n batches in flight (the service's local path). Batches go to its process pool as the job
  function `worker.jobs.evaluate_batch`, which times itself like on an RQ worker.

For each kind, with 1 and then 2 workers: evaluations per second for a stream of batches of
`paper-voxel` robots (4x4x4, 10 s simulated; generation 0 of seed 1, cycled) and of `quick`
robots (3x3x3, 3 s simulated), batch size 4; the per-batch overhead: worker time not spent
computing, (workers x wall - sum of the worker-side `seconds` in the result payloads) / batches;
the CPU this process (the API side of the queue) and redis-server spend per batch; and the CPU
other processes used meanwhile (a quiet machine reads 0.0x cores). With one worker it also times
the round trip of a trivially small batch (one 1x1x1 robot, 20 steps), enqueue to result, minus
that job's own `seconds`, and counts the Redis commands per job. Then, forking worker with 2
workers, batch sizes 1, 2, 4, 8 and 16 robots per job (192 robots per stream). It also times
what a fork costs in a warm process like a worker's. Every fitness is checked against the
serial evaluator. Every process started here is stopped at the end (`--kinds` picks kinds).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import rq
from benchlib import OtherLoad, cpu_model, free_port, redis_version
from rq import Worker

from softevo.core.config import resolve
from softevo.core.physics.evaluation import PoolEvaluator, SerialEvaluator, evaluate_robot_files
from softevo.core.robots.robot import VoxelRobot
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.robots.settings import sim_settings
from softevo.core.search.evolution import Evolution
from softevo.worker.evaluator import RQEvaluator
from softevo.worker.jobs import evaluate_batch
from softevo.worker.queue import connect

#: One process running RQ's WorkerPool: load the kernels, then fork the workers.
WORKER_POOL = """
import sys
from rq import SimpleWorker, Worker
from rq.worker_pool import WorkerPool
from softevo.core.physics.evaluation import warm_up
from softevo.worker.queue import QUEUE, SERIALIZER, connect
url, n, kind = sys.argv[1], int(sys.argv[2]), sys.argv[3]
warm_up()
pool = WorkerPool([QUEUE], connection=connect(url), num_workers=n, serializer=SERIALIZER,
                  worker_class={"simple": SimpleWorker, "fork": Worker}[kind])
pool.start(logging_level="WARNING")
"""

# (fitness, worker-side seconds) of one batch
Call = Callable[[list[dict[str, Any]], str], tuple[np.ndarray, float]]


def stop(process: subprocess.Popen, grace: float = 15) -> None:
    """SIGTERM (RQ's warm shutdown), then SIGKILL to the process group it was started in."""
    if process.poll() is None:
        process.terminate()
        with contextlib.suppress(subprocess.TimeoutExpired):
            process.wait(grace)
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGKILL)  # its group: work horses, pool children
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.wait(10)


@contextlib.contextmanager
def redis_server(workdir: Path) -> Iterator[str]:
    """A private redis-server on a free port (no persistence); yields its URL."""
    port = free_port()
    command = ["redis-server", "--port", str(port), "--bind", "127.0.0.1"]
    command += ["--save", "", "--appendonly", "no", "--dir", str(workdir)]
    process = subprocess.Popen(
        command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    url = f"redis://127.0.0.1:{port}/0"
    try:
        deadline = time.monotonic() + 10
        while True:
            try:
                connect(url).ping()
                break
            except Exception:
                if time.monotonic() > deadline:
                    raise RuntimeError(f"redis-server did not start on port {port}") from None
                time.sleep(0.05)
        yield url
    finally:
        stop(process)


class Workers:
    """RQ worker processes of one kind on the private Redis."""

    def __init__(self, kind: str, url: str, workdir: Path) -> None:
        self.kind, self.url, self.workdir = kind, url, workdir
        self.processes: list[subprocess.Popen] = []
        self.count = 0

    def _spawn(self, command: list[str], log_name: str) -> None:
        with (self.workdir / log_name).open("w") as log:
            self.processes.append(
                subprocess.Popen(
                    command,
                    stdout=log,
                    stderr=subprocess.STDOUT,
                    start_new_session=True,
                    env={k: v for k, v in os.environ.items() if not k.startswith("SOFTEVO_")},
                )
            )

    def scale(self, n: int) -> None:
        """Run n workers of this kind and wait until all are registered (kernels warm)."""
        if self.kind.startswith("pool/"):  # a WorkerPool has a fixed size: start a new one
            self.stop()
            command = [sys.executable, "-c", WORKER_POOL, self.url, str(n), self.kind[5:]]
            self._spawn(command, f"pool-{self.kind[5:]}-{n}.log")
        else:
            for i in range(self.count, n):
                name = f"{self.kind}-{i + 1}"
                command = [sys.executable, "-P", "-m", "softevo.cli", "worker", "--url", self.url]
                command += ["--worker-class", self.kind, "--name", name, "--log-level", "warning"]
                self._spawn(command, f"worker-{name}.log")
        connection = connect(self.url)
        deadline = time.monotonic() + 120
        while Worker.count(connection=connection) < n:
            for process in self.processes:
                if process.poll() is not None:
                    logs = "".join(p.read_text()[-2000:] for p in self.workdir.glob("*.log"))
                    raise RuntimeError(f"{self.kind} worker exited ({process.returncode}):\n{logs}")
            if time.monotonic() > deadline:
                raise RuntimeError(f"{n} {self.kind} workers not registered in 120 s")
            time.sleep(0.05)
        connection.close()
        self.count = n

    def stop(self) -> None:
        for process in self.processes:
            stop(process)
        self.processes, self.count = [], 0
        connection = connect(self.url)
        connection.flushall()  # forget the stopped workers, their jobs and results
        connection.close()


@dataclass
class Stream:
    wall: float  # s, median of the repeats
    compute: float  # s, sum of worker-side seconds of that run
    batches: int
    robots: int
    workers: int
    client_cpu: float  # s, CPU of this process (the evaluator's threads) in that run
    redis_cpu: float  # s, CPU of redis-server in that run
    other: float  # cores used by other processes, the most in any of the repeats

    @property
    def rate(self) -> float:
        return self.robots / self.wall

    @property
    def overhead_ms(self) -> float:
        """Worker time per batch not spent computing."""
        return 1000 * (self.workers * self.wall - self.compute) / self.batches

    @property
    def efficiency(self) -> float:
        return self.compute / (self.workers * self.wall)

    @property
    def compute_ms_per_robot(self) -> float:
        return 1000 * self.compute / self.robots


def run_stream(
    call: Call,
    files: list[dict[str, Any]],
    reference: np.ndarray,
    batch: int,
    robots: int,
    workers: int,
    threads: int,
    repeats: int,
    redis_url: str | None = None,
) -> Stream:
    """`robots` robots (files cycled) in batches of `batch`, `threads` batches in flight."""
    order = [i % len(files) for i in range(robots)]
    batches = [order[i : i + batch] for i in range(0, robots, batch)]

    def once(tag: str, todo: list[list[int]]) -> tuple[float, float, float, float, float]:
        def one(item: tuple[int, list[int]]) -> float:
            number, members = item
            fitness, seconds = call([files[i] for i in members], f"bench-{tag}-{number}")
            if not np.array_equal(fitness, reference[members], equal_nan=True):
                raise AssertionError(f"batch {number}: fitness differs from the serial evaluator")
            return seconds

        cpu, redis = time.process_time(), redis_cpu(redis_url)
        other = OtherLoad().start()
        started = time.perf_counter()
        with ThreadPoolExecutor(max_workers=min(threads, len(todo))) as executor:
            compute = sum(executor.map(one, enumerate(todo)))
        wall = time.perf_counter() - started
        cpu, redis = time.process_time() - cpu, redis_cpu(redis_url) - redis
        return wall, compute, cpu, redis, other.stop()

    once(uuid.uuid4().hex[:8], batches[: 2 * workers])  # untimed: every worker has run a job
    runs = sorted(once(uuid.uuid4().hex[:8], batches) for _ in range(repeats))
    wall, compute, client_cpu, redis_seconds, _ = runs[len(runs) // 2]
    other = max(run[4] for run in runs)
    return Stream(wall, compute, len(batches), robots, workers, client_cpu, redis_seconds, other)


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


def redis_calls(url: str, reset: bool = False) -> dict[str, int]:
    """Commands Redis has run since the last reset, by name (INFO commandstats)."""
    connection = connect(url)
    try:
        if reset:
            connection.config_resetstat()
            return {}
        stats = connection.info("commandstats")
        return {k.removeprefix("cmdstat_"): int(v["calls"]) for k, v in stats.items()}
    finally:
        connection.close()


def round_trip(
    call: Call, tiny: dict[str, Any], count: int, url: str | None = None
) -> tuple[float, float, float, dict[str, float]]:
    """Median enqueue-to-result time of a one-robot, 20-step batch, its compute, the p90 of the
    difference (ms), one batch at a time; and with `url`, Redis commands per job by name."""
    tag = uuid.uuid4().hex[:8]
    for i in range(3):
        call([tiny], f"tiny-{tag}-warm{i}")
    if url:
        redis_calls(url, reset=True)
    trips, computes = [], []
    for i in range(count):
        started = time.perf_counter()
        _, seconds = call([tiny], f"tiny-{tag}-{i}")
        trips.append(time.perf_counter() - started)
        computes.append(seconds)
    calls = redis_calls(url) if url else {}
    calls.pop("info", None)  # our own INFO commandstats
    gaps = sorted(1000 * (t - c) for t, c in zip(trips, computes, strict=True))
    return (
        1000 * statistics.median(trips),
        1000 * statistics.median(computes),
        gaps[int(0.9 * (len(gaps) - 1))],
        {name: calls[name] / count for name in sorted(calls, key=lambda n: -calls[n])},
    )


def fork_cost(tiny: dict[str, Any], count: int = 21) -> tuple[float, float, float, float]:
    """What a forking worker pays per job, measured in this process (kernels loaded, like a
    warm worker): median ms of fork + exit + wait; of fork + evaluating the tiny robot in the
    child + exit + wait; of evaluating it here; and this process's resident memory (MiB)."""

    def timed(child: Callable[[], None]) -> float:
        times = []
        for _ in range(count):
            started = time.perf_counter()
            pid = os.fork()
            if pid == 0:
                try:
                    child()
                finally:
                    os._exit(0)
            os.waitpid(pid, 0)
            times.append(time.perf_counter() - started)
        return 1000 * statistics.median(times)

    bare = timed(lambda: None)
    with_job = timed(lambda: evaluate_robot_files([tiny]))
    here = []
    for _ in range(count):
        started = time.perf_counter()
        evaluate_robot_files([tiny])
        here.append(time.perf_counter() - started)
    rss = int(Path("/proc/self/statm").read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    return bare, with_job, 1000 * statistics.median(here), rss / 2**20


def rq_call(evaluator: RQEvaluator) -> Call:
    def call(files: list[dict[str, Any]], key: str) -> tuple[np.ndarray, float]:
        result = evaluator.evaluate_batch(files, key)
        return result.fitness, result.seconds

    return call


def pool_call(pool: PoolEvaluator) -> Call:
    # The pool's own executor (what `PoolEvaluator.evaluate_batch` submits a batch to), given
    # the RQ job function so the worker side times itself exactly as an RQ worker does.
    def call(files: list[dict[str, Any]], key: str) -> tuple[np.ndarray, float]:
        payload = pool._pool.submit(evaluate_batch, key, files).result()
        fitness = [np.nan if v is None else v for v in payload["fitness"]]
        return np.array(fitness, dtype=np.float64), float(payload["seconds"])

    return call


BATCH_SIZES = (1, 2, 4, 8, 16)
LABELS = {
    "fork": "RQ Worker (fork)",
    "simple": "RQ SimpleWorker",
    "pool/simple": "WorkerPool, SimpleWorker",
    "pool/fork": "WorkerPool, Worker (fork)",
    "local": "PoolEvaluator (no Redis)",
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="1 repeat, 48 (96) robots per stream")
    parser.add_argument("--robots", type=int, default=96, help="robots per timed stream (96)")
    parser.add_argument(
        "--sweep-robots", type=int, default=192, help="robots per batch-size stream (192)"
    )
    parser.add_argument("--repeats", type=int, default=3, help="timed streams, median (3)")
    parser.add_argument("--trips", type=int, default=30, help="tiny round trips (30)")
    parser.add_argument("--kinds", default="fork,simple,pool/simple,pool/fork,local")
    args = parser.parse_args()
    if args.quick:
        args.robots, args.sweep_robots, args.repeats, args.trips = 48, 96, 1, 10
    kinds = args.kinds.split(",")
    if shutil.which("redis-server") is None:
        sys.exit("bench/rq_workers.py needs the redis-server binary")

    paper = Evolution.start(resolve({"preset": "paper-voxel", "seed": 1}))
    quick = Evolution.start(resolve({"preset": "quick", "seed": 1}))
    robot_sets = {
        "paper-voxel": [robot_to_json(paper.robot(item)) for item in paper.individuals()],
        "quick": [robot_to_json(quick.robot(item)) for item in quick.individuals()],
    }
    serial = SerialEvaluator()
    references = {name: serial.evaluate_batch(files).fitness for name, files in robot_sets.items()}
    tiny = robot_to_json(
        VoxelRobot((1, 1, 1), ("hard",), sim=sim_settings({"duration": 0.01, "settle_time": 0}))
    )
    forked = fork_cost(tiny)  # before any thread or subprocess of ours exists

    print(
        f"machine: {os.cpu_count()} cores, {cpu_model()}, load {os.getloadavg()[0]:.2f}, "
        f"Python {platform.python_version()}, rq {rq.__version__}, "
        f"redis-server {redis_version()}"
    )
    print(
        f"streams: {args.robots} robots per stream (generation 0 of seed 1, cycled), "
        f"median of {args.repeats}; up to 64 batches in flight on RQ, n on the local pool"
    )
    print("overhead = (workers x wall - worker-side compute) / batches; client CPU: this")
    print("process's CPU per batch (enqueue, wait, decode; on the local pool, feeding it);")
    print("Redis CPU: redis-server's CPU per batch; other: cores used meanwhile by processes")
    print("outside this benchmark (other jobs, steal time; the most in any repeat)\n")

    streams: dict[tuple[str, str, int, int], Stream] = {}
    sweep: dict[tuple[str, int], Stream] = {}
    trips: dict[str, tuple[float, float, float, dict[str, float]]] = {}

    def measure(kind: str, call: Call, n: int, threads: int, url: str | None = None) -> None:
        if n == 1:
            trips[kind] = round_trip(call, tiny, args.trips, url)
        for name, files in robot_sets.items():
            streams[kind, name, n, 4] = run_stream(
                call, files, references[name], 4, args.robots, n, threads, args.repeats, url
            )
            s = streams[kind, name, n, 4]
            print(
                f"  {LABELS[kind]:<27}{n} worker{'s' if n > 1 else ' '} {name:<12}"
                f"{s.rate:8.1f} eval/s  overhead {s.overhead_ms:6.1f} ms/batch  "
                f"other load {s.other:.2f} cores",
                flush=True,
            )
        if kind == "fork" and n == 2:
            for batch in BATCH_SIZES:
                for name, files in robot_sets.items():
                    sweep[name, batch] = run_stream(
                        call,
                        files,
                        references[name],
                        batch,
                        args.sweep_robots,
                        n,
                        threads,
                        args.repeats,
                        url,
                    )

    with tempfile.TemporaryDirectory(prefix="softevo-bench-worker-") as tmp:
        workdir = Path(tmp)
        with redis_server(workdir) as url:
            for kind in kinds:
                if kind == "local":
                    for n in (1, 2):
                        with PoolEvaluator(n) as pool:
                            measure(kind, pool_call(pool), n, threads=n)
                    continue
                workers = Workers(kind, url, workdir)
                evaluator = RQEvaluator(url)
                try:
                    for n in (1, 2):
                        workers.scale(n)
                        measure(kind, rq_call(evaluator), n, threads=64, url=url)
                finally:
                    evaluator.close()
                    workers.stop()

    bare, with_job, here, rss = forked
    print(
        f"\nfork in a warm process ({rss:.0f} MiB resident, kernels loaded), median of 21: "
        f"fork + exit + wait {bare:.2f} ms; with the tiny job in the child {with_job:.2f} ms; "
        f"the tiny job without a fork {here:.2f} ms"
    )
    print(
        f"\nRound trip of a trivially small batch (1 robot, 20 steps), 1 worker, one at a time, "
        f"{args.trips} trips"
    )
    print(
        f"{'kind':<28}{'round trip (ms)':>16}{'compute (ms)':>14}{'overhead (ms)':>15}"
        f"{'p90 (ms)':>10}"
    )
    for kind, (trip, compute, p90, _) in trips.items():
        print(f"{LABELS[kind]:<28}{trip:>16.2f}{compute:>14.2f}{trip - compute:>15.2f}{p90:>10.2f}")
    print("\nRedis commands per job (both sides: enqueue, result, RQ's bookkeeping), same trips")
    for kind, (*_, calls) in trips.items():
        if calls:
            top = ", ".join(f"{name} {per_job:.1f}" for name, per_job in list(calls.items())[:8])
            print(f"{LABELS[kind]:<28}{sum(calls.values()):>6.1f}   {top}")

    for name in robot_sets:
        local = {n: streams.get(("local", name, n, 4)) for n in (1, 2)}
        print(f"\n{name} robots, batches of 4, {args.robots} robots per stream")
        print(
            f"{'kind':<28}{'workers':>8}{'eval/s':>9}{'vs local':>9}{'compute/robot':>15}"
            f"{'overhead/batch':>16}{'efficiency':>11}{'client CPU':>12}"
            f"{'Redis CPU':>11}{'other':>7}"
        )
        for kind in kinds:
            for n in (1, 2):
                s = streams[kind, name, n, 4]
                versus = f"{s.rate / local[n].rate:.3f}" if local[n] else "-"
                redis = f"{1000 * s.redis_cpu / s.batches:.2f} ms" if kind != "local" else "-"
                print(
                    f"{LABELS[kind]:<28}{n:>8}{s.rate:>9.1f}{versus:>9}"
                    f"{s.compute_ms_per_robot:>12.1f} ms{s.overhead_ms:>13.1f} ms"
                    f"{s.efficiency:>11.1%}{1000 * s.client_cpu / s.batches:>9.2f} ms"
                    f"{redis:>11}{s.other:>7.2f}"
                )

    if "fork" in kinds:
        for name in robot_sets:
            print(
                f"\nBatch size, RQ Worker (fork), 2 workers, {name} robots, "
                f"{args.sweep_robots} robots per stream"
            )
            print(
                f"{'robots/job':>10}{'jobs':>6}{'eval/s':>9}{'compute/robot':>15}"
                f"{'overhead/batch':>16}{'overhead share':>16}{'other':>7}"
            )
            for batch in BATCH_SIZES:
                s = sweep[name, batch]
                print(
                    f"{batch:>10}{s.batches:>6}{s.rate:>9.1f}{s.compute_ms_per_robot:>12.1f} ms"
                    f"{s.overhead_ms:>13.1f} ms{1 - s.efficiency:>16.1%}"
                    f"{s.other:>7.2f}"
                )

    every = [*streams.values(), *sweep.values()]
    print(
        f"\nother load: CPU of processes outside this benchmark, cores, the most in any timed "
        f"stream: {max(s.other for s in every):.2f} (a quiet machine reads 0.0x)"
    )


if __name__ == "__main__":
    main()
