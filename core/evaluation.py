"""The in-process evaluators (serial, local process pool) and the job function every backend runs.

The interface is `softevo.core.evaluator.Evaluator`; RQ workers (`softevo.worker`) are the other
backend. Payloads
are plain data (robot-file dicts, `softevo.robot/1`), never live objects, and a robot's fitness
does not depend on which batch, process or machine simulated it (the kernels are bit-identical
across batches), so every backend gives the same learning curve.

A robot that cannot be built or whose simulation blows up has fitness NaN: failed, never 0.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import socket
import threading
import time
import weakref
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any

import numpy as np

from softevo.core import batching
from softevo.core.evaluator import BatchDroppedError, BatchResult, Evaluator
from softevo.core.nulls import from_nulls, to_null
from softevo.core.physics import simulate, simulate_batch
from softevo.core.physics.simulate import DEFAULT_LANES
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
    return [None if robot is None else to_null(next(speeds)) for robot in robots]


def _timed(name: str, evaluate: Callable[[], np.ndarray]) -> BatchResult:
    started = time.perf_counter()
    fitness = evaluate()
    return BatchResult(fitness, f"{name}@{socket.gethostname()}", time.perf_counter() - started)


class SerialEvaluator(Evaluator):
    """Everything in the calling process, one batch at a time (batches from several threads
    wait for each other)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()

    def evaluate_batch(
        self, robot_files: Sequence[dict[str, Any]], key: str | None = None
    ) -> BatchResult:
        files = list(robot_files)
        with self._lock:
            return _timed("SerialEvaluator", lambda: from_nulls(evaluate_robot_files(files)))

    def capacity(self) -> int:
        return 1

    def close(self) -> None:
        pass


def warm_up() -> None:
    """Load (or compile) the physics kernels, so no evaluation pays for it."""
    robot = VoxelRobot((1, 1, 1), ("hard",), sim=sim_settings({"duration": 0.01, "settle_time": 0}))
    simulate_batch([robot])
    simulate(robot)


#: How much a pool process yields to the process that owns the pool (os.nice): simulations use
#: every core, and the API in the parent must still answer at once.
POOL_NICENESS = 10


def start_pool_process() -> None:
    """A pool process's start: it exits when its parent dies, however it dies (a SIGKILLed
    server leaves no simulations running under init), yields the CPU to its parent, then loads
    the kernels."""
    parent = os.getppid()
    with contextlib.suppress(OSError):
        os.nice(POOL_NICENESS)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(0)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()
    warm_up()


class PoolEvaluator(Evaluator):
    """A local pool of worker processes (default: one per core), each warmed up once, fed by
    one queue of every caller's batches (`softevo.core.batching`): at most one task a process
    at a time, a task being whole batches of one kind up to the kernel's SIMD width, so the
    batches of several runs that wait for a busy pool leave together in fuller kernel calls.

    If a process dies (killed, out of memory), the pool is rebuilt and each batch of the task
    tried once more, alone; a batch that kills its process twice raises. `drop(prefix)` (a
    cancelled run) answers the run's batches at once: waiting ones leave the queue, and if one
    runs in a task of its own, the pool's processes are replaced (a simulation cannot be
    interrupted inside the kernel); other runs' batches that were in them run again on the new
    ones, uncounted, with the same result."""

    def __init__(self, processes: int | None = None, lanes: int = DEFAULT_LANES) -> None:
        self.processes = processes or os.cpu_count() or 1
        if self.processes < 1:
            raise ValueError(f"processes must be >= 1, got {self.processes}")
        self._lock = threading.RLock()  # guards everything below (a callback may run inside)
        self._queue = batching.Queue(lanes)
        self._pool = self._new_pool()
        self._tasks: dict[Future[list[float | None]], list[batching.Request]] = {}
        self._dropped: set[str] = set()  # key prefixes given up
        self._replaced: weakref.WeakSet[ProcessPoolExecutor] = weakref.WeakSet()  # by `drop`
        self._closed = False
        self.tasks = 0  # kernel calls handed to the processes so far (batches merged or not)

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            max_workers=self.processes,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=start_pool_process,
        )

    def evaluate_batch(
        self, robot_files: Sequence[dict[str, Any]], key: str | None = None
    ) -> BatchResult:
        """Thread-safe: any number of callers; their batches share the pool's tasks."""
        request = batching.Request(list(robot_files), key or "")
        if not request.files:
            return BatchResult(np.empty(0), f"PoolEvaluator@{socket.gethostname()}", 0.0)
        with self._lock:
            self._refuse_dropped(request.key)
            self._queue.put(request)
            self._fill()
        return _timed("PoolEvaluator", lambda: from_nulls(request.future.result()))

    def _fill(self) -> None:
        """Hand the queue's tasks to the pool while a process is free (under the lock; called
        by a caller that queued a batch and by every task that lands: no thread in between)."""
        while self._queue and len(self._tasks) < self.processes and not self._closed:
            task = self._queue.take()
            pool = self._pool
            try:
                future = pool.submit(evaluate_robot_files, batching.task_files(task))
            except BrokenProcessPool:
                self._failed(task, pool)
                continue
            except Exception as error:  # never leave a caller waiting
                for request in task:
                    request.future.set_exception(error)
                continue
            self._tasks[future] = task
            self.tasks += 1
            future.add_done_callback(lambda done, pool=pool: self._landed(done, pool))

    def _landed(self, future: Future[list[float | None]], pool: ProcessPoolExecutor) -> None:
        with self._lock:
            task = self._tasks.pop(future)
            if future.cancelled() or future.exception() is not None:
                self._failed(task, pool)
            else:
                batching.split_results(task, future.result())
            self._fill()

    def _failed(self, task: list[batching.Request], pool: ProcessPoolExecutor) -> None:
        """A task whose process died: each batch again, alone (uncounted after a drop)."""
        if self._closed:
            for request in task:
                if not request.future.done():
                    request.future.set_exception(RuntimeError("the pool was closed"))
            return
        replaced = pool in self._replaced
        if not replaced and self._pool is pool:  # the first to notice rebuilds it
            pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._new_pool()
        for request in task:
            if request.future.done():
                continue
            if not replaced and request.attempt == 2:
                request.future.set_exception(BrokenProcessPool(f"batch {request.key} killed "
                                                               "its process twice"))  # fmt: skip
                continue
            request.attempt += 0 if replaced else 1
            request.alone = True
            self._queue.put(request, first=True)

    def _refuse_dropped(self, key: str) -> None:
        if key and any(key.startswith(prefix) for prefix in self._dropped):
            raise BatchDroppedError(f"batch {key} was dropped")

    def drop(self, key_prefix: str) -> None:
        with self._lock:
            self._dropped.add(key_prefix)
            dropped = BatchDroppedError(f"the batches of {key_prefix}* were dropped")
            for request in self._queue.remove(key_prefix):
                request.future.set_exception(dropped)
            only_theirs = False
            for task in self._tasks.values():
                mine = [r for r in task if r.key.startswith(key_prefix)]
                for request in mine:
                    if not request.future.done():
                        request.future.set_exception(dropped)
                only_theirs |= bool(mine) and len(mine) == len(task)
            if not only_theirs:  # a task shared with other runs finishes for them
                return
            old, self._pool = self._pool, self._new_pool()
            self._replaced.add(old)
        for process in list(getattr(old, "_processes", {}).values()):  # stdlib keeps them here
            with contextlib.suppress(OSError):
                process.kill()
        old.shutdown(wait=False, cancel_futures=True)

    def capacity(self) -> int:
        return self.processes

    def close(self) -> None:
        with self._lock:
            self._closed = True
            for request in self._queue.remove(""):
                request.future.set_exception(RuntimeError("the pool was closed"))
            pool = self._pool
        pool.shutdown(wait=True, cancel_futures=True)


def make_evaluator(processes: int | None = None) -> Evaluator:
    """The in-process default: serial for one process, otherwise a local pool."""
    if processes == 1:
        return SerialEvaluator()
    return PoolEvaluator(processes)
