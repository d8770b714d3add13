"""What `bench/scaling.py` measures around a run, and its profile: this process's CPU by
thread, Redis's counters, the workers' CPU, the queue's depth, the workers' busy time and gaps,
and where yappi finds this process's time going."""

from __future__ import annotations

import contextlib
import itertools
import math
import os
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchlib import OtherLoad
from redis import Redis

from softevo.worker.queue import QUEUE, connect

BENCH = Path(__file__).resolve().parent


def middle(start: float, end: float) -> tuple[float, float]:
    """The run's middle 80 %: no start, no tail."""
    return start + 0.1 * (end - start), end - 0.1 * (end - start)


def mid_busy(spans: list[tuple[str, float, float]], low: float, high: float, workers: int) -> float:
    """The busy fraction between `low` and `high`: simulation seconds within / (workers x
    length)."""
    inside = sum(max(0.0, min(high, s + d) - max(low, s)) for _, s, d in spans)
    return inside / (workers * (high - low))


def median_gap(spans: list[tuple[str, float, float]]) -> float:
    """The median time (s) from the end of a worker's job to the start of its next one: RQ's
    own work on both sides, the result's push, and any wait for a job to be queued."""
    by_worker: dict[str, list[tuple[float, float]]] = {}
    for worker, started, seconds in spans:
        by_worker.setdefault(worker, []).append((started, seconds))
    gaps = sorted(
        b[0] - (a[0] + a[1])
        for jobs in by_worker.values()
        for a, b in itertools.pairwise(sorted(jobs))
    )
    return gaps[len(gaps) // 2] if gaps else math.nan


class QueueWatch:
    """Samples, every 50 ms on its own thread and connection, whether any job waits on the
    queue; its Redis commands and read events (one each a sample) and CPU are taken out of the
    figures by `drive`."""

    def __init__(self, url: str) -> None:
        self.connection, self.samples = connect(url), []  # (unix time, jobs waiting)
        self.cpu, self.stopping = 0.0, threading.Event()
        self.thread = threading.Thread(target=self._watch, name="queue-watch", daemon=True)
        self.thread.start()

    def _watch(self) -> None:
        key = f"rq:queue:{QUEUE}"
        while not self.stopping.wait(0.05):
            self.samples.append((time.time(), self.connection.llen(key)))
        self.cpu = time.thread_time()

    def stop(self) -> None:
        self.stopping.set()
        self.thread.join()
        self.connection.close()

    def empty(self, low: float, high: float) -> float:
        """The share of samples between `low` and `high` that found no job waiting."""
        found = [waiting for at, waiting in self.samples if low <= at <= high]
        return sum(waiting == 0 for waiting in found) / max(1, len(found))


def process_cpu(pids: list[int]) -> float:
    """CPU seconds (user + system) the processes have used so far."""
    ticks = 0
    for pid in pids:
        with contextlib.suppress(OSError):
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
            ticks += int(fields[11]) + int(fields[12])
    return ticks / os.sysconf("SC_CLK_TCK")


def thread_cpu() -> dict[int, tuple[str, float]]:
    """Each live thread of this process: its name and CPU seconds so far."""
    found = {}
    for thread in threading.enumerate():
        with contextlib.suppress(OSError, OverflowError, TypeError):
            clock = time.pthread_getcpuclockid(thread.ident)  # type: ignore[arg-type]
            found[thread.ident or 0] = (thread.name, time.clock_gettime(clock))
    return found


def redis_counters(connection: Redis) -> tuple[int, int, float]:
    """Commands run (less INFO), read events, CPU seconds of redis-server so far. Between two
    calls on one connection, 3 of the read events are theirs (`drive` takes them out)."""
    stats = connection.info("commandstats")
    commands = sum(int(v["calls"]) for k, v in stats.items() if k != "cmdstat_info")
    reads = int(connection.info("stats")["total_reads_processed"])
    cpu = connection.info("cpu")
    return commands, reads, float(cpu["used_cpu_user"]) + float(cpu["used_cpu_sys"])


class Meter:
    """This process's CPU (less the queue watch's) by thread, Redis's counters (less this
    bench's own commands), the workers' CPU and other processes' load, across one run."""

    def __init__(self, url: str, pids: list[int]) -> None:
        self.pids, self.counters = pids, connect(url)
        self.threads, self.redis = thread_cpu(), redis_counters(self.counters)
        self.workers, self.other = process_cpu(pids), OtherLoad().start()
        self.watch = QueueWatch(url)
        self.cpu, self.wall, self.start = time.process_time(), time.perf_counter(), time.time()

    def stop(self) -> dict[str, float]:
        cpu, wall = time.process_time() - self.cpu, time.perf_counter() - self.wall
        after, redis, samples = thread_cpu(), redis_counters(self.counters), len(self.watch.samples)
        workers, other = process_cpu(self.pids) - self.workers, self.other.stop()
        self.watch.stop()
        self.counters.close()
        spent: dict[str, float] = {}  # by thread name: CPU since the start (or its birth)
        for ident, (name, seconds) in after.items():
            before = self.threads.get(ident, ("", 0.0))
            key = "batch" if name.startswith("batch") else name
            spent[key] = spent.get(key, 0.0) + seconds - (before[1] if before[0] == name else 0)
        low, high = middle(self.start, self.start + wall)
        return {
            "wall": wall,
            "cpu": cpu - spent.get("queue-watch", 0.0),
            "driver": cpu - sum(spent.values()),
            "batches": spent.get("batch", 0.0),
            "commands": redis[0] - self.redis[0] - samples,
            "reads": redis[1] - self.redis[1] - samples - 3,
            "redis": redis[2] - self.redis[2],
            "workers": workers,
            "other": other,
            "empty": self.watch.empty(low, high),
            "low": low,
            "high": high,
        }


def profile(drive_once: Any, label: str, top: int = 25) -> None:
    """`drive_once()` under yappi (CPU clock, every thread); prints where the time went."""
    import yappi

    yappi.clear_stats()
    yappi.set_clock_type("cpu")
    yappi.start(builtins=True, profile_threads=True)
    figures = drive_once()
    yappi.stop()
    stats = yappi.get_func_stats()
    total = sum(stat.tsub for stat in stats)
    per_birth = 1e3 * total / figures.births
    print(
        f"\n{label}: yappi, CPU clock, every thread: {total:.2f} s of own time "
        f"({per_birth:.3f} ms per birth; unprofiled figures above)"
    )
    places: dict[str, float] = {}
    for stat in stats:
        places[place(stat.module)] = places.get(place(stat.module), 0.0) + stat.tsub
    for name, seconds in sorted(places.items(), key=lambda item: -item[1]):
        if seconds >= 0.01 * total:
            print(f"  {seconds / total:6.1%}  {name}")
    print(f"  own time, the top {top} functions:")
    for stat in sorted(stats, key=lambda s: -s.tsub)[:top]:
        print(f"  {stat.tsub / total:6.1%} {stat.ncall:>8} calls  {place(stat.module)}:{stat.name}")
    print("  inclusive time of softevo's functions, the top 25:")
    mine = [stat for stat in stats if "softevo" in place(stat.module)]
    for stat in sorted(mine, key=lambda s: -s.ttot)[:25]:
        print(f"  {stat.ttot / total:6.1%} {stat.ncall:>8} calls  {place(stat.module)}:{stat.name}")
    yappi.clear_stats()


def place(module: str) -> str:
    """A module's file as a short name: softevo/..., the package of a library, or the file."""
    path = Path(module)
    parts = path.parts
    for anchor in ("site-packages", "dist-packages"):
        if anchor in parts:
            return "/".join(parts[parts.index(anchor) + 1 :][:2])
    if path.is_relative_to(BENCH.parent):  # this checkout (installed editable)
        inside = path.relative_to(BENCH.parent)
        return ("" if inside.parts[0] == "bench" else "softevo/") + str(inside)
    return path.name if path.suffix else module


@dataclass
class Figures:
    label: str
    births: int
    robots: int
    jobs: int
    wall: float
    busy: float  # the stand-in's simulation seconds
    mid: float  # the busy fraction in the middle 80 % of the wall
    empty: float  # the share of the middle 80 % with no job waiting on the queue
    gap: float  # the median time (s) between a worker's jobs
    cpu: float  # this process
    cpu_driver: float
    cpu_batches: float
    commands: int
    reads: int
    redis_cpu: float
    workers_cpu: float
    other: float  # cores used by processes outside this bench
    best: float | None

    def line(self, workers: int) -> str:
        per_birth = 1e3 / self.births
        return (
            f"{self.label:<22}{self.births:>7}{self.robots:>7}{self.robots / self.jobs:>7.2f}"
            f"{self.wall:>8.1f}{self.busy / (workers * self.wall):>7.3f}{self.mid:>6.3f}"
            f"{self.empty:>6.2f}{1e3 * self.gap:>6.0f}"
            f"{self.cpu * per_birth:>9.3f}{self.cpu_driver * per_birth:>8.3f}"
            f"{self.cpu_batches * per_birth:>8.3f}{self.commands / self.robots:>8.1f}"
            f"{self.reads / self.robots:>7.1f}{1e3 * self.redis_cpu / self.jobs:>7.2f}"
            f"{1e3 * self.workers_cpu / self.jobs:>8.2f}{self.other:>6.2f}"
            f"{'' if self.best is None else f'{self.best:>6.3f}'}"
        )


HEADER = (
    f"{'run':<22}{'births':>7}{'robots':>7}{'r/job':>7}{'wall s':>8}{'busy':>7}{'mid':>6}"
    f"{'q=0':>6}{'gap':>6}"
    f"{'CPU/b ms':>9}{'driver':>8}{'batches':>8}{'cmd/r':>8}{'rd/r':>7}{'redis':>7}"
    f"{'workers':>8}{'other':>6}{'best':>6}"
)
