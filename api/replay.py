"""Replays served by the API: computed once per (robot, fps) and remembered, on the RQ workers
when the service has them (the API process then never loads the physics), else in two niced
processes of the API's own, which hand back JSON bytes (the API only splices them).

A replay is asked for on a plain GET, so it is bounded: at most `MAX_POSITIONS` mass positions
(`softevo.core.replay`), its fps rounded to a bucket, at most `RUNNING_AT_ONCE` simulated at
the same moment (more are refused with 503, never queued on a request thread), and the last few
kept within `CACHED_BYTES`, so a dashboard refreshing, or many people watching one run,
simulates a robot once.
"""

from __future__ import annotations

import json
import math
import multiprocessing
import threading
from collections import OrderedDict
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from fastapi import Response

from softevo.core.limits import MAX_REPLAY_POSITIONS
from softevo.core.robot_file import robot_to_json

#: Most mass positions one replay carries (frames x masses).
MAX_POSITIONS = MAX_REPLAY_POSITIONS
#: Replays remembered (the newest), and the most bytes they may hold together (estimated).
CACHED = 8
CACHED_BYTES = 256 * 2**20
#: Replays simulated at the same moment; one more asked for is refused (503), not queued, so
#: no request thread waits on a simulation and `/healthz` and the curve stay fast.
RUNNING_AT_ONCE = 2
#: Frame rates replays are recorded at: a request's fps is rounded to the nearest (in ratio), so
#: any fps does not force a new simulation.
FPS_BUCKETS = (0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 15.0, 20.0, 30.0, 60.0, 120.0)

#: (robot file, fps, max positions) -> replay; None: in this process (`use_workers` sets it)
Remote = Callable[[dict[str, Any], float, int], dict[str, Any]]
_remote: Remote | None = None
_cache: OrderedDict[tuple[str, float], bytes] = OrderedDict()
_lock = threading.Lock()
_computing: dict[tuple[str, float], threading.Lock] = {}
_slots = threading.BoundedSemaphore(RUNNING_AT_ONCE)


class ReplayUnavailableError(RuntimeError):
    """The workers gave no replay (none live in time, the job failed): 503, saying why."""


class ReplayBusyError(RuntimeError):
    """RUNNING_AT_ONCE replays are being simulated: try again in a moment (503)."""


def use_workers(remote: Remote | None) -> None:
    """Compute replays with `remote` (the RQ workers) from now on; None: in this process."""
    global _remote
    _remote = remote


def fps_bucket(fps: float) -> float:
    return min(FPS_BUCKETS, key=lambda bucket: abs(math.log(bucket / fps)))


def replay(robot: Any, fps: float) -> bytes:
    """Frames at (up to) `fps` per simulated second, rounded to a bucket, as JSON bytes."""
    key = _key(robot, fps)
    fps = key[1]
    with _lock:
        if key in _cache:
            _cache.move_to_end(key)
            return _cache[key]
        computing = _computing.setdefault(key, threading.Lock())
    with computing:  # one simulation per key, however many ask at once
        with _lock:
            if key in _cache:
                return _cache[key]
        if not _slots.acquire(blocking=False):
            with _lock:
                _computing.pop(key, None)
            raise ReplayBusyError(
                f"{RUNNING_AT_ONCE} replays are being simulated; try again in a few seconds"
            )
        try:
            data = _simulate(robot, fps)
        except BaseException:
            with _lock:
                _computing.pop(key, None)
            raise
        finally:
            _slots.release()
        _remember(key, data)
    return data


def replay_response(robot: Any, fps: float, **head: Any) -> Response:
    """The replay as a JSON response, `head` (run id, fitness, ...) first: bytes spliced, never
    a million positions turned into objects in this process (that would stall its event loop)."""
    encoded = replay(robot, fps)
    prefix = json.dumps(head, separators=(",", ":"), allow_nan=False)[:-1].encode()
    body = encoded if not head else prefix + b"," + encoded[1:]
    return Response(content=body, media_type="application/json")


def _key(robot: Any, fps: float) -> tuple[str, float]:
    return json.dumps(robot_to_json(robot), sort_keys=True), fps_bucket(fps)


def _remember(key: tuple[str, float], data: bytes) -> None:
    """Cached before its lock goes, so a late caller finds it; the oldest go past the bounds."""
    with _lock:
        _cache[key] = data
        while len(_cache) > 1 and (
            len(_cache) > CACHED or sum(len(v) for v in _cache.values()) > CACHED_BYTES
        ):
            _cache.popitem(last=False)
        _computing.pop(key, None)


def _simulate(robot: Any, fps: float) -> bytes:
    if _remote is not None:
        try:
            data = _remote(robot_to_json(robot), fps, MAX_POSITIONS)
        except RuntimeError as error:
            raise ReplayUnavailableError(str(error)) from None
        return json.dumps(data, separators=(",", ":"), allow_nan=False).encode()
    from softevo.core.replay import replay_json

    try:  # in a process of its own: its CPU and its encoding leave this one free
        return _processes().submit(replay_json, robot_to_json(robot), fps, MAX_POSITIONS).result()
    except BrokenProcessPool:
        shutdown()
        raise ReplayUnavailableError("the replay's process died (out of memory?)") from None


_pool: ProcessPoolExecutor | None = None


def _processes() -> ProcessPoolExecutor:
    """The replays' own processes (RUNNING_AT_ONCE, niced, gone with this one), made on the
    first replay this process computes."""
    global _pool
    from softevo.core.evaluation import start_pool_process

    with _lock:
        if _pool is None:
            _pool = ProcessPoolExecutor(
                RUNNING_AT_ONCE,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=start_pool_process,
            )
        return _pool


def shutdown() -> None:
    """Stop the replays' processes (the server stops, or one of them died)."""
    global _pool
    with _lock:
        pool, _pool = _pool, None
    if pool is not None:
        pool.shutdown(wait=False, cancel_futures=True)


def in_own_process(function: Callable[..., Any], *args: Any) -> Any:
    """`function(*args)` in one of the replays' processes, counted against RUNNING_AT_ONCE like a
    replay (one more is refused with ReplayBusyError, never queued on a request thread)."""
    if not _slots.acquire(blocking=False):
        raise ReplayBusyError(
            f"{RUNNING_AT_ONCE} replays are being simulated; try again in a few seconds"
        )
    try:
        return _processes().submit(function, *args).result()
    except BrokenProcessPool:
        shutdown()
        raise ReplayUnavailableError("the replay's process died (out of memory?)") from None
    finally:
        _slots.release()
