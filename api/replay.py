"""A replay: one robot simulated once more with its frames recorded, for a 3D viewer."""

from __future__ import annotations

import math
from typing import Any

from core.robot_file import robot_to_json


def replay(robot: Any, fps: float) -> dict[str, Any]:
    """Frames at `fps` per simulated second; the physics loads only when a replay is asked for."""
    from core.physics import simulate

    record_every = max(1, round(1.0 / (fps * robot.sim.dt)))
    result, trajectory = simulate(robot, record_every=record_every)
    assert trajectory is not None
    return {
        "speed": result.speed if math.isfinite(result.speed) else None,
        "robot": robot_to_json(robot),
        **trajectory.to_json(),
    }
