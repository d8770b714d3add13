"""The in-process evaluators (serial, local process pool) and the job function every backend runs.

The interface is `core.evaluator.Evaluator`; RQ workers (`worker/`) are the other backend. Payloads
are plain data (robot-file dicts, `softevo.robot/1`), never live objects, and a robot's fitness
does not depend on which batch, process or machine simulated it (the kernels are bit-identical
across batches), so every backend gives the same learning curve.

A robot that cannot be built or whose simulation blows up has fitness NaN: failed, never 0.
"""

from __future__ import annotations

import itertools
import math
import multiprocessing
import os
import socket
import threading
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any

import numpy as np

from softevo.core.evaluator import BatchResult, Evaluator
from softevo.core.physics import simulate, simulate_batch
from softevo.core.robot import Robot, VoxelRobot
from softevo.core.robot_file import RobotFileError, parse_robot
from softevo.core.settings import sim_settings


def evaluate_robot_files(robot_files: Sequence[dict[str, Any]]) -> list[float | None]:
    """The job function: robot files in, speeds out (None for a failed robot, JSON-safe)."""
    robots: list[Robot | None] = []
    for document in robot_files:
        try:
            robots.append(parse_robot(document))
        except RobotFileError:
            robots.append(None)
    built = [robot for robot in robots if robot is not None]
    speeds = iter(result.speed for result in simulate_batch(built)) if built else iter(())
    return [None if robot is None else _finite_or_none(next(speeds)) for robot in robots]


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _to_array(values: Sequence[float | None]) -> np.ndarray:
    return np.array([math.nan if v is None else v for v in values], dtype=np.float64)


class _Timed:
    """`evaluate_batch` for the in-process backends: `evaluate`, timed, named by host."""

    def evaluate(self, robot_files: Sequence[dict[str, Any]]) -> np.ndarray:
        raise NotImplementedError

    def evaluate_batch(
        self, robot_files: Sequence[dict[str, Any]], key: str | None = None
    ) -> BatchResult:
        started = time.perf_counter()
        fitness = self.evaluate(robot_files)
        name = f"{type(self).__name__}@{socket.gethostname()}"
        return BatchResult(fitness, name, time.perf_counter() - started)


class SerialEvaluator(_Timed):
    """Everything in the calling process, one batch at a time."""

    concurrency = 1

    def workers(self) -> int:
        return 1

    def evaluate(self, robot_files: Sequence[dict[str, Any]]) -> np.ndarray:
        return _to_array(evaluate_robot_files(list(robot_files)))

    def close(self) -> None:
        pass


def warm_up() -> None:
    """Load (or compile) the physics kernels, so no evaluation pays for it."""
    robot = VoxelRobot((1, 1, 1), ("hard",), sim=sim_settings({"duration": 0.01, "settle_time": 0}))
    simulate_batch([robot])
    simulate(robot)


class PoolEvaluator(_Timed):
    """A local pool of worker processes (default: one per core), each warmed up once.

    A batch is cut into contiguous chunks, about two per process so a slow chunk does not leave
    a core idle, but none smaller than `min_chunk` robots, so a small batch stays one batch
    across the kernel's SIMD lanes in one process; results come back in input order.
    """

    def __init__(self, processes: int | None = None, min_chunk: int = 1) -> None:
        self.processes = processes or os.cpu_count() or 1
        self.concurrency = self.processes
        self.min_chunk = max(1, min_chunk)
        if self.processes < 1:
            raise ValueError(f"processes must be >= 1, got {self.processes}")
        self._lock = threading.Lock()
        self._pool = self._new_pool()

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            max_workers=self.processes,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=warm_up,
        )

    def evaluate(self, robot_files: Sequence[dict[str, Any]]) -> np.ndarray:
        """Thread-safe. If a pool process dies (killed, out of memory), the pool is rebuilt and
        the batch tried once more; a batch that kills its process twice raises."""
        files = list(robot_files)
        if not files:
            return np.empty(0)
        n_chunks = min(2 * self.processes, math.ceil(len(files) / self.min_chunk))
        bounds = np.linspace(0, len(files), n_chunks + 1).round().astype(int)
        chunks = [files[start:stop] for start, stop in itertools.pairwise(bounds)]
        for attempt in (1, 2):
            pool = self._pool
            try:
                results = list(pool.map(evaluate_robot_files, chunks))
                return _to_array([value for chunk in results for value in chunk])
            except BrokenProcessPool:
                if attempt == 2:
                    raise
                with self._lock:
                    if self._pool is pool:  # the first thread to notice rebuilds it
                        pool.shutdown(wait=False, cancel_futures=True)
                        self._pool = self._new_pool()
        raise AssertionError("unreachable")

    def workers(self) -> int:
        return self.processes

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)

    def __enter__(self) -> PoolEvaluator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def make_evaluator(processes: int | None = None, min_chunk: int = 1) -> Evaluator:
    """The in-process default: serial for one process, otherwise a local pool."""
    if processes == 1:
        return SerialEvaluator()
    return PoolEvaluator(processes, min_chunk)
