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
    names = {
        "speed": "speed",
        "forward": "forward speed",
        "climb": "climb rate",
        "efficiency": "efficiency",
    }
    return f"{names[objective]} ({OBJECTIVES[objective][1]})"


#: Every measure of a simulation's record (`SimResult.measures`) a run may name in `objectives`:
#: name -> (unit, goal it is usually given, hypervolume reference, ideal), both bounds in the
#: measure's own units. The reference is a value worse than almost any robot's: 0 for what is
#: maximised (a robot that does not move spans no volume); for cost_of_transport and energy, well
#: above what a random 4x4x4 paper-voxel robot measures (48 of them, seed 0: cost of transport
#: median about 1,300, largest about 27,000; energy largest about 44,000 J). The ideal is a value
#: better than any robot here is expected to reach, the 1 of the normalised hypervolume (the
#: reference is its 0; docs/evolution.md "Normalised hypervolume" says why each): 1 m/s is about
#: four times the fastest gait measured (0.27 m/s) and what a body that falls over in a short
#: simulation reaches, 10 m that speed over the default 10 s, 0.2 m/s of climb a 1 m/s crawler
#: up task-slope's 10 degrees, 0.1 m/J a cost of transport of 0.1 for a 10 kg body; no work, no
#: mass and no parts are the bounds of the others.
#: A run may give its own of either (`reference`, `ideal`).
MEASURES: dict[str, tuple[str, str, float | None, float]] = {
    "speed": ("m/s", "max", 0.0, 1.0),
    "forward_speed": ("m/s", "max", 0.0, 1.0),
    "climb_rate": ("m/s", "max", 0.0, 0.2),
    "distance": ("m", "max", 0.0, 10.0),
    "efficiency": ("m/J", "max", 0.0, 0.1),
    "cost_of_transport": ("1", "min", 100_000.0, 0.0),
    "energy": ("J", "min", 1_000_000.0, 0.0),
    "heading": ("degrees", "max", None, 180.0),
    "stable": ("1", "max", None, 1.0),
    "total_mass": ("kg", "min", None, 0.0),
    "masses": ("1", "min", None, 0.0),
    "springs": ("1", "min", None, 0.0),
}

#: Measures the simulation only takes when asked to count the actuators' work.
ENERGY_MEASURES = frozenset({"energy", "cost_of_transport", "efficiency"})

#: How a reader is told the unit of a measure that is a pure number (MEASURES' "1").
PURE_NUMBERS: dict[str, str] = {
    "cost_of_transport": "dimensionless",
    "stable": "0 or 1",
    "masses": "count",
    "springs": "count",
}


def measure_unit(measure: str) -> str:
    """A measure's unit as a reader wants it on an axis: never the bare "1"."""
    unit = MEASURES[measure][0]
    return PURE_NUMBERS.get(measure, "dimensionless") if unit == "1" else unit


def measure_label(measure: str) -> str:
    """`cost of transport (dimensionless)`: a measure named with its unit, for axes and titles."""
    return f"{measure.replace('_', ' ')} ({measure_unit(measure)})"
