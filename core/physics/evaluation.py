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
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import CancelledError, Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from softevo.core.evaluator import BatchResult, Evaluator, Measures, refuse_dropped
from softevo.core.nulls import record_text, to_null, to_null_record
from softevo.core.objectives import NEEDS_ENERGY
from softevo.core.physics import simulate, simulate_batch
from softevo.core.robots.robot import Robot, VoxelRobot
from softevo.core.robots.robot_file import RobotFileError, file_energy, file_objective, parse_robot
from softevo.core.robots.settings import sim_settings


def evaluate_robot_files(robot_files: Sequence[dict[str, Any]]) -> Measures:
    """The job function: robot files in, each one's `fitness` (its file's `objective`, speed by
    default; None: failed) and record of `measures` (`SimResult.measures`, None for a value not
    measured, the whole record None for a robot that could not be built) out, JSON-safe, with
    each record's JSON text (`texts`), made here so that the service stores it as it comes."""
    robots: list[Robot | None] = []
    for document in robot_files:
        try:
            robots.append(parse_robot(document))
        except RobotFileError:
            robots.append(None)
    objectives = [file_objective(d) for d, r in zip(robot_files, robots, strict=True) if r]
    built = [robot for robot in robots if robot is not None]
    energy = any(objective in NEEDS_ENERGY for objective in objectives) or any(
        file_energy(document) for document, robot in zip(robot_files, robots, strict=True) if robot
    )
    results = simulate_batch(built, energy=energy, small_alone=True) if built else []
    simulated = iter(zip(results, objectives, strict=True))
    fitness: list[float | None] = []
    measures: list[dict[str, float | None] | None] = []
    for robot in robots:
        result, objective = next(simulated) if robot is not None else (None, "")
        fitness.append(None if result is None else to_null(result.measure(objective)))
        measures.append(None if result is None else to_null_record(result.measures()))
    texts = [None if record is None else record_text(record) for record in measures]
    return {"fitness": fitness, "measures": measures, "texts": texts}


def _timed(name: str, evaluate: Callable[[], Measures]) -> BatchResult:
    started = time.perf_counter()
    measured = evaluate()
    seconds = time.perf_counter() - started
    return BatchResult.measured(measured, f"{name}@{socket.gethostname()}", seconds)


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
            return _timed("SerialEvaluator", lambda: evaluate_robot_files(files))

    def capacity(self) -> int:
        return 1

    def close(self) -> None:
        pass


def warm_up(batched: bool = True, alone: bool = True) -> None:
    """Load (or compile) the physics kernels, so no evaluation pays for it: the batched one and
    the one for a robot alone (each compiles on its own, so two processes can share the work)."""
    robot = VoxelRobot((1, 1, 1), ("hard",), sim=sim_settings({"duration": 0.01, "settle_time": 0}))
    if batched:
        simulate_batch([robot])
    if alone:
        simulate(robot)


#: How much a pool process yields to the process that owns the pool (os.nice): simulations use
#: every core, and the API in the parent must still answer at once.
POOL_NICENESS = 10


def _release_fork_server() -> None:
    """Close this process's copy of the pipe end whose closing tells the fork server that the
    process owning it died (multiprocessing hands it to every process it forks): with copies
    open in the pool, the fork server and its pool would outlive a SIGKILLed server."""
    from multiprocessing import forkserver

    server = getattr(forkserver, "_forkserver", None)
    fd = getattr(server, "_forkserver_alive_fd", None)
    if fd is not None:
        with contextlib.suppress(OSError):
            os.close(fd)
        if server is not None:
            server._forkserver_alive_fd = None


def start_pool_process() -> None:
    """A pool process's start: it exits when its parent dies, however it dies (a SIGKILLed
    server leaves no simulations running under init: its fork server, the parent of a forked
    pool process, exits with it), yields the CPU to the server, then loads the kernels (at once
    where the fork server loaded them)."""
    _release_fork_server()
    parent = os.getppid()
    with contextlib.suppress(OSError):
        os.nice(POOL_NICENESS)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(0)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()
    warm_up()


#: The fork server's preload: the module whose import loads the kernels.
PRELOAD = "softevo.core.physics.preload"


def pool_context() -> multiprocessing.context.BaseContext:
    """How pool processes start: forked from a fork server that has imported the physics and
    loaded the kernels once (a later pool starts about 30x quicker, bench/pool_start.py), or spawned
    where there is no fork server (Windows) or it cannot start (it needs a socket in a writable
    temporary folder). Either way a process starts clean of the parent's threads and
    connections, and imports the main module."""
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    from multiprocessing import forkserver  # a POSIX module: imported where there is one

    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload([PRELOAD])
    try:
        with _safe_path():
            forkserver.ensure_running()  # started now, not in the first submit where it can fail
    except OSError:
        return multiprocessing.get_context("spawn")
    return context


_ENVIRON = threading.Lock()


@contextlib.contextmanager
def _safe_path() -> Iterator[None]:
    """Start the fork server with Python's safe path (`PYTHONSAFEPATH`, as `python -P`). It runs
    as `python -c ...`, which puts the working directory first on its path, and Python 3.11 does
    not apply the `sys_path` it is handed: in a checkout's root the source folder `softevo/`
    (which holds no `core`) would stand in for the installed package."""
    with _ENVIRON:
        before = os.environ.get("PYTHONSAFEPATH")
        os.environ["PYTHONSAFEPATH"] = "1"
        try:
            yield
        finally:
            if before is None:
                del os.environ["PYTHONSAFEPATH"]
            else:
                os.environ["PYTHONSAFEPATH"] = before


class PoolEvaluator(Evaluator):
    """A local pool of worker processes (default: one per core), each warmed up once. A batch
    runs in one process, across the kernel's SIMD lanes; the generation step cuts a generation
    into at least `capacity()` batches and keeps them in flight together, one per process.

    `drop(prefix)` (a cancelled run) cancels the run's batches not yet handed to a process and,
    if one of them runs or waits in the pool's call queue, replaces the pool: its processes are
    killed (a simulation cannot be interrupted inside the kernel) and other runs' batches that
    were in it run again on the new one, uncounted, with the same result."""

    def __init__(self, processes: int | None = None) -> None:
        self.processes = processes or os.cpu_count() or 1
        if self.processes < 1:
            raise ValueError(f"processes must be >= 1, got {self.processes}")
        self._lock = threading.Lock()
        self._pool = self._new_pool()
        self._batches: dict[Future[Measures], str] = {}  # in the pool: key each
        self._dropped: set[str] = set()  # key prefixes given up
        self._replaced: weakref.WeakSet[ProcessPoolExecutor] = weakref.WeakSet()  # by `drop`

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            max_workers=self.processes,
            mp_context=pool_context(),
            initializer=start_pool_process,
        )

    def evaluate_batch(
        self, robot_files: Sequence[dict[str, Any]], key: str | None = None
    ) -> BatchResult:
        """Thread-safe. If a pool process dies (killed, out of memory), the pool is rebuilt and
        the batch tried once more; a batch that kills its process twice raises."""
        files = list(robot_files)
        return _timed("PoolEvaluator", lambda: self._run(files, key or ""))

    def _run(self, files: list[dict[str, Any]], key: str) -> Measures:
        if not files:
            return {"fitness": [], "measures": []}
        attempt = 1
        while True:
            with self._lock:
                refuse_dropped(key, self._dropped)
                pool = self._pool
            future: Future[Measures] | None = None
            try:
                with self._lock:
                    future = pool.submit(evaluate_robot_files, files)
                    self._batches[future] = key
                return future.result()
            except (BrokenProcessPool, CancelledError):
                with self._lock:
                    refuse_dropped(key, self._dropped)
                    if pool in self._replaced:  # another run's cancel: not this batch's
                        continue
                    if attempt == 2:
                        raise
                    attempt += 1
                    if self._pool is pool:  # the first thread to notice rebuilds it
                        pool.shutdown(wait=False, cancel_futures=True)
                        self._pool = self._new_pool()
            finally:
                with self._lock:
                    if future is not None:
                        self._batches.pop(future, None)

    def drop(self, key_prefix: str) -> None:
        with self._lock:
            self._dropped.add(key_prefix)
            mine = [future for future, key in self._batches.items() if key.startswith(key_prefix)]
            running = [future for future in mine if not future.cancel()]
            if not running:
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
        self._pool.shutdown(wait=True, cancel_futures=True)


def make_evaluator(processes: int | None = None) -> Evaluator:
    """The in-process default: serial for one process, otherwise a local pool."""
    if processes == 1:
        return SerialEvaluator()
    return PoolEvaluator(processes)
