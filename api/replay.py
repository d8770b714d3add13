"""Replays served by the API: computed once per (robot, fps) and remembered, on the RQ workers
when the service has them (the API process then never loads the physics), else in this process.

A replay is asked for on a plain GET, so it is bounded (at most `MAX_POSITIONS` mass positions,
`softevo.core.replay`) and the last few are kept, so a dashboard refreshing, or many people
watching one run, simulates a robot once.
"""

from __future__ import annotations

import json
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

from softevo.core.limits import MAX_REPLAY_POSITIONS
from softevo.core.robot_file import robot_to_json

#: Most mass positions one replay carries (frames x masses).
MAX_POSITIONS = MAX_REPLAY_POSITIONS
#: Replays remembered (the newest), each at most MAX_POSITIONS positions.
CACHED = 8

#: (robot file, fps, max positions) -> replay; None: in this process (`use_workers` sets it)
Remote = Callable[[dict[str, Any], float, int], dict[str, Any]]
_remote: Remote | None = None
_cache: OrderedDict[tuple[str, float], dict[str, Any]] = OrderedDict()
_lock = threading.Lock()
_computing: dict[tuple[str, float], threading.Lock] = {}


def use_workers(remote: Remote | None) -> None:
    """Compute replays with `remote` (the RQ workers) from now on; None: in this process."""
    global _remote
    _remote = remote


def replay(robot: Any, fps: float) -> dict[str, Any]:
    """Frames at (up to) `fps` per simulated second."""
    key = (json.dumps(robot_to_json(robot), sort_keys=True), fps)
    with _lock:
        if key in _cache:
            _cache.move_to_end(key)
            return _cache[key]
        computing = _computing.setdefault(key, threading.Lock())
    with computing:  # one simulation per key, however many ask at once
        with _lock:
            if key in _cache:
                return _cache[key]
        try:
            data = _simulate(robot, fps)
        except BaseException:
            with _lock:
                _computing.pop(key, None)
            raise
        with _lock:  # cached before its lock goes, so a late caller finds it
            _cache[key] = data
            while len(_cache) > CACHED:
                _cache.popitem(last=False)
            _computing.pop(key, None)
    return data


class ReplayUnavailableError(RuntimeError):
    """The workers gave no replay (none live in time, the job failed): 503, saying why."""


def _simulate(robot: Any, fps: float) -> dict[str, Any]:
    if _remote is not None:
        try:
            return _remote(robot_to_json(robot), fps, MAX_POSITIONS)
        except RuntimeError as error:
            raise ReplayUnavailableError(str(error)) from None
    from softevo.core.replay import replay_frames

    return replay_frames(robot, fps, MAX_POSITIONS)
