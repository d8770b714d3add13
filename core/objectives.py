"""Objectives: which number of a simulation is a robot's fitness (run setting `objective`).

Every simulation measures all of them (`SimResult`); a run picks one. `speed` is the paper's and
the default, so a run that names no objective keeps its curve to the last digit. All are measured
from `settle_time` to the end of the simulation (docs/physics.md "Measures").
"""

from __future__ import annotations

from typing import Literal

#: g in the cost of transport (m/s^2), whatever the simulation's gravity.
STANDARD_GRAVITY = 9.81

Objective = Literal["speed", "forward", "climb", "efficiency"]

#: objective -> the SimResult attribute that is its fitness
OBJECTIVE_MEASURES: dict[str, str] = {
    "speed": "speed",
    "forward": "forward_speed",
    "climb": "climb_rate",
    "efficiency": "efficiency",
}

#: objective -> (what it rewards, unit): for `GET /presets`, plots and --help
OBJECTIVES: dict[str, tuple[str, str]] = {
    "speed": ("horizontal speed of the centre of mass, in any direction", "m/s"),
    "forward": ("net displacement along +x per second (up the slope, stairs, over hurdles)", "m/s"),
    "climb": ("rise of the centre of mass per second", "m/s"),
    "efficiency": ("horizontal distance per joule of actuator work", "m/J"),
}

#: objectives whose fitness needs the actuators' work measured (the kernels' extra loop)
NEEDS_ENERGY = frozenset({"efficiency"})


def objective_label(objective: str) -> str:
    """`forward speed (m/s)`-style axis label."""
    names = {"speed": "speed", "forward": "forward speed", "climb": "climb rate",
             "efficiency": "efficiency"}  # fmt: skip
    return f"{names[objective]} ({OBJECTIVES[objective][1]})"
