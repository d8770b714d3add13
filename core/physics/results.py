"""What a simulation gives back: `SimResult` (the measures of one robot) and `Trajectory` (its
mass positions over time, for replays). Kept apart from the engine so readers of results need
not load it."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from softevo.core.nulls import to_null, to_nulls
from softevo.core.objectives import OBJECTIVE_MEASURES, STANDARD_GRAVITY


@dataclass(frozen=True)
class Trajectory:
    """Mass positions over time, for replays: frames [F, M, 3] (m) at `times` [F] (s)."""

    times: np.ndarray
    frames: np.ndarray
    springs: np.ndarray  # [S, 2] mass indices
    stiffness: np.ndarray  # [S] (N/m), to colour passive springs by material
    phase: np.ndarray | None = None  # [S] actuation phase (rad), NaN for a passive spring

    def to_json(self) -> dict:
        phase = (
            None
            if self.phase is None
            else [None if (q := to_null(p)) is None else round(q, 6) for p in self.phase.tolist()]
        )
        return {
            "format": "softevo.trajectory/1",
            "times": [round(t, 9) for t in self.times.tolist()],
            "springs": self.springs.tolist(),
            "stiffness": self.stiffness.tolist(),
            "phase": phase,
            "frames": np.round(self.frames, 6).tolist(),
        }


@dataclass(frozen=True)
class SimResult:
    """Outcome of one simulation. Fitness is `speed`: NaN when the simulation blew up."""

    masses: int
    springs: int
    steps: int
    com_start: tuple[float, float, float]  # centre of mass at settle_time (m)
    com_end: tuple[float, float, float]  # centre of mass at the end (m)
    distance: float  # net horizontal displacement of the centre of mass (m)
    speed: float  # distance / measured time (m/s)
    wall_seconds: float
    stable: bool  # every position finite at the end, no spring blown past MAX_STRETCH
    final_positions: np.ndarray  # [M, 3] (m)
    forward_speed: float = math.nan  # net displacement along +x / measured time (m/s)
    climb_rate: float = math.nan  # rise of the centre of mass / measured time (m/s)
    energy: float = math.nan  # actuators' work over the measured time (J; NaN: not measured)
    total_mass: float = math.nan  # (kg)
    #: direction of the centre of mass's net horizontal displacement, degrees in [-180, 180]
    #: counter-clockwise from +x (90: +y); 0 for no displacement, NaN when not stable
    heading: float = math.nan

    @property
    def cost_of_transport(self) -> float:
        """energy / (total mass x g x distance): dimensionless, lower is cheaper."""
        weight_distance = self.total_mass * STANDARD_GRAVITY * self.distance
        if not self.stable or math.isnan(self.energy) or weight_distance <= 0:
            return math.nan
        return self.energy / weight_distance

    @property
    def efficiency(self) -> float:
        """distance per joule of actuator work (m/J); 0 for a robot that did no work."""
        if not self.stable or math.isnan(self.energy):
            return math.nan
        return self.distance / self.energy if self.energy > 0 else 0.0

    def measure(self, objective: str) -> float:
        """The fitness of this result under `objective` (softevo.core.objectives)."""
        return float(getattr(self, OBJECTIVE_MEASURES[objective]))

    def measures(self) -> dict[str, float]:
        """Every number this simulation measured, by name (NaN: not measured, or not stable):
        the record kept per individual (job results, the run's cache, the store, population.csv,
        the API), which objectives and behavioural descriptors read by name. The one place that
        defines them; a new measure is one line here and one in docs/physics.md ("Measures and
        objectives"). Not measures: `wall_seconds` and `steps` (of the run, not the robot)."""
        return {
            "distance": self.distance,
            "speed": self.speed,
            "forward_speed": self.forward_speed,
            "climb_rate": self.climb_rate,
            "heading": self.heading,
            "energy": self.energy,
            "cost_of_transport": self.cost_of_transport,
            "efficiency": self.efficiency,
            "stable": 1.0 if self.stable else 0.0,
            "total_mass": self.total_mass,
            "masses": float(self.masses),
            "springs": float(self.springs),
        }

    def to_json(self) -> dict:
        """The `softevo simulate` output (no final positions)."""
        return {
            "masses": self.masses,
            "springs": self.springs,
            "steps": self.steps,
            "com_start": to_nulls(self.com_start),  # null where the simulation blew up
            "com_end": to_nulls(self.com_end),
            "distance": to_null(self.distance),
            "speed": to_null(self.speed),
            "forward_speed": to_null(self.forward_speed),
            "climb_rate": to_null(self.climb_rate),
            "energy": to_null(self.energy),
            "cost_of_transport": to_null(self.cost_of_transport),
            "wall_seconds": self.wall_seconds,
            "stable": self.stable,
        }
