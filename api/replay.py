"""Replays served by the API: computed once per (robot, fps) and remembered, on the RQ workers
when the service has them (the API process then never loads the physics), else in this process.

A replay is asked for on a plain GET, so it is bounded: at most `MAX_POSITIONS` mass positions
(`softevo.core.replay`), its fps rounded to a bucket, at most `RUNNING_AT_ONCE` simulated at
the same moment (more are refused with 503, never queued on a request thread), and the last few
kept within `CACHED_BYTES`, so a dashboard refreshing, or many people watching one run,
simulates a robot once.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import threading
from collections import OrderedDict
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
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
_cache: OrderedDict[tuple[str, float], dict[str, Any]] = OrderedDict()
_sizes: dict[tuple[str, float], int] = {}
_lock = threading.Lock()
_computing: dict[tuple[str, float], threading.Lock] = {}
_slots = threading.BoundedSemaphore(RUNNING_AT_ONCE)
#: a cached replay's JSON, made on first use (with the replay it encodes)
_encoded: dict[tuple[str, float], tuple[dict[str, Any], bytes]] = {}


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


def replay(robot: Any, fps: float) -> dict[str, Any]:
    """Frames at (up to) `fps` per simulated second, rounded to a bucket."""
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
    """The replay as a JSON response, `head` (run id, fitness, ...) first. The replay's JSON is
    made once per replay and kept, in this request's thread: a replay is megabytes of numbers,
    and encoding it on the server's event loop would stall every other request for seconds."""
    data = replay(robot, fps)
    key = _key(robot, fps)
    with _lock:
        kept = _encoded.get(key)
    if kept is not None and kept[0] is data:
        encoded = kept[1]
    else:
        encoded = json.dumps(data, separators=(",", ":"), allow_nan=False).encode()
        with _lock:
            if _cache.get(key) is data:  # kept as long as the replay is
                _encoded[key] = (data, encoded)
    prefix = json.dumps(head, separators=(",", ":"), allow_nan=False)[:-1].encode()
    body = encoded if not head else prefix + b"," + encoded[1:]
    return Response(content=body, media_type="application/json")


def _key(robot: Any, fps: float) -> tuple[str, float]:
    return json.dumps(robot_to_json(robot), sort_keys=True), fps_bucket(fps)


def _remember(key: tuple[str, float], data: dict[str, Any]) -> None:
    """Cached before its lock goes, so a late caller finds it; the oldest go past the bounds."""
    frames = data.get("frames") or [[]]
    # Python lists of floats: about 110 bytes a position (three floats and their list)
    size = 110 * len(frames) * len(frames[0]) + 100 * len(data.get("springs") or [])
    with _lock:
        _cache[key], _sizes[key] = data, size
        while len(_cache) > 1 and (
            len(_cache) > CACHED or sum(_sizes[k] for k in _cache) > CACHED_BYTES
        ):
            old, _ = _cache.popitem(last=False)
            _sizes.pop(old, None)
            _encoded.pop(old, None)
        _computing.pop(key, None)


def _simulate(robot: Any, fps: float) -> dict[str, Any]:
    if _remote is not None:
        try:
            return _remote(robot_to_json(robot), fps, MAX_POSITIONS)
        except RuntimeError as error:
            raise ReplayUnavailableError(str(error)) from None
    from softevo.core.replay import replay_frames

    # on a thread of lower priority: a replay uses a core for seconds, the API must not wait
    return _simulators.submit(replay_frames, robot, fps, MAX_POSITIONS).result()


def _lower_priority() -> None:
    """Linux schedules threads on their own: this one yields to the API's (nice 10)."""
    with contextlib.suppress(AttributeError, OSError):
        os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), 10)


_simulators = ThreadPoolExecutor(
    RUNNING_AT_ONCE, thread_name_prefix="replay", initializer=_lower_priority
)
