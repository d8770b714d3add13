"""A replay: one robot simulated once more with its frames recorded, for a 3D viewer.

A replay is computed in the API process on a plain GET, so it is bounded and remembered: the
frame rate is lowered until the frames hold at most `MAX_POSITIONS` mass positions (a 512-voxel
robot over 60 s would otherwise be hundreds of megabytes of JSON), and the last few replays are
kept, so a dashboard refreshing, or many people watching one run, simulates a robot once.
"""

from __future__ import annotations

import json
import math
import threading
from collections import OrderedDict
from typing import Any

from softevo.core.nulls import to_null
from softevo.core.robot import build_mechanics
from softevo.core.robot_file import robot_to_json

#: Most mass positions one replay carries (frames x masses), about 20 MB of JSON.
MAX_POSITIONS = 1_000_000
#: Replays remembered (the newest), each at most MAX_POSITIONS positions.
CACHED = 8

_cache: OrderedDict[tuple[str, float], dict[str, Any]] = OrderedDict()
_lock = threading.Lock()
_computing: dict[tuple[str, float], threading.Lock] = {}


def record_every(robot: Any, masses: int, fps: float) -> int:
    """Steps between frames: `fps` frames per simulated second, fewer if the frames would hold
    more than MAX_POSITIONS positions."""
    sim = robot.sim
    wanted = max(1, round(1.0 / (fps * sim.dt)))
    frames_allowed = max(2, MAX_POSITIONS // max(1, masses) - 1)
    return max(wanted, math.ceil(sim.n_steps / frames_allowed))


def replay(robot: Any, fps: float) -> dict[str, Any]:
    """Frames at (up to) `fps` per simulated second; the physics loads only when asked for."""
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


def _simulate(robot: Any, fps: float) -> dict[str, Any]:
    from softevo.core.physics import simulate

    mechanics = build_mechanics(robot)
    every = record_every(robot, mechanics.n_masses, fps)
    result, trajectory = simulate(mechanics, record_every=every)
    assert trajectory is not None
    return {
        "speed": to_null(result.speed),
        "fps": 1.0 / (every * robot.sim.dt),
        "robot": robot_to_json(robot),
        **trajectory.to_json(),
    }
