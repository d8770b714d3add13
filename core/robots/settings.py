"""Simulation settings: every physical number the engine uses, with the paper's values as defaults.

Where the paper gives a number (dt, damping, friction, ground stiffness, mass, the two spring
stiffnesses, gravity) it is the default here. Where the paper is silent (duration, drop height,
settling, how actuation genes map to rest lengths) the default is our choice; `docs/physics.md`
says why. Every value is validated on construction so a bad setting is refused before anything runs.
"""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from softevo.core.robots.step import critical_step, sure_unstable_step
from softevo.core.robots.terrain import Flat, Terrain

#: Largest number of integration steps one simulation may take (duration / dt).
MAX_STEPS = 20_000_000

#: The physics profiles: the values a profile gives the settings that a file or request leaves
#: out. `paper` is the paper's arithmetic (velocities times 0.99 each step at dt = 0.5 ms: a drag
#: of 20.1 s^-1 that doubles when dt halves); `physical` gives every damping in physical units
#: and derives the step from the stiffest material, so results converge as dt shrinks
#: (docs/physics.md). A file without `profile` is `paper`, as every file written before it was.
PROFILES: dict[str, dict[str, Any]] = {
    "paper": {
        "dt": 0.0005,
        "damping": 0.99,
        "drag": 0.0,
        "material_damping": 0.0,
        "contact_damping": 0.0,
    },
    "physical": {
        "dt": None,
        "damping": 1.0,
        "drag": 0.5,
        "material_damping": 1.0,
        "contact_damping": 1.0,
    },
}


class SimSettings(BaseModel):
    """Physical and numerical settings of one simulation. Units are SI (m, s, kg, N)."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)

    profile: Literal["paper", "physical"] = Field(
        "paper", description="physics profile: the defaults of dt and the damping (PROFILES)"
    )
    dt: float | None = Field(
        0.0005,
        gt=0,
        le=0.01,
        description="integration time step (s); null: dt_fraction of the critical step",
    )
    dt_fraction: float = Field(
        0.8, gt=0, le=1, description="dt as a fraction of the critical step when dt is null"
    )
    duration: float = Field(10.0, gt=0, le=3600, description="simulated time (s)")
    gravity: float = Field(-9.81, ge=-1000, le=1000, description="acceleration along z (m/s^2)")
    damping: float = Field(
        0.99,
        gt=0,
        le=1,
        description="legacy: factor on every velocity each step (the paper's 0.99); 1.0 = none",
    )
    drag: float = Field(
        0.0, ge=0, le=1e4, description="global velocity damping (s^-1), exp(-drag dt) a step"
    )
    material_damping: float = Field(
        0.0, ge=0, le=10, description="damping of every spring, as a ratio to critical damping"
    )
    contact_damping: float = Field(
        0.0, ge=0, le=10, description="damping of the ground contact, ratio to critical damping"
    )
    ground_stiffness: float = Field(
        10000.0, ge=0, le=1e8, description="penalty spring of the ground at z = 0 (N/m)"
    )
    friction: float = Field(0.6, ge=0, le=10, description="Coulomb friction coefficient")
    mass: float = Field(0.1, gt=0, le=1e4, description="mass of every point (kg)")
    edge_length: float = Field(1.0, gt=0, le=100, description="voxel edge length (m)")
    drop_height: float = Field(
        0.0, ge=0, le=1000, description="height of the robot's lowest point at t = 0 (m)"
    )
    omega: float = Field(
        1.0, ge=0, le=1e4, description="angular frequency w of voxel actuation (rad/s)"
    )
    soft_stiffness: float = Field(500.0, ge=0, le=1e8, description="soft voxel springs (N/m)")
    hard_stiffness: float = Field(2000.0, ge=0, le=1e8, description="hard voxel springs (N/m)")
    actuated_stiffness: float = Field(
        2000.0, ge=0, le=1e8, description="springs of sine / neg_sine voxels (N/m)"
    )
    offset_scale: float = Field(
        0.1, ge=0, le=1, description="rest-length offset per unit of gene a (fraction of length)"
    )
    amplitude_scale: float = Field(
        0.1, ge=0, le=1, description="rest-length amplitude per unit of gene b (fraction)"
    )
    settle_time: float = Field(
        1.0, ge=0, description="time (s) at which the fitness clock and com_start start"
    )
    terrain: Terrain = Field(
        default_factory=Flat,
        description="the ground: flat (default), slope, steps, rough or hurdles (docs/tasks.md)",
    )

    @model_validator(mode="before")
    @classmethod
    def _profile_defaults(cls, data: Any) -> Any:
        """Settings left out take their profile's values (an unknown profile is refused by the
        field's own check)."""
        if isinstance(data, dict):
            defaults = PROFILES.get(data.get("profile", "paper"), {})
            data = {**defaults, **data}
        return data

    @model_validator(mode="after")
    def _check_times(self) -> SimSettings:
        if self.settle_time >= self.duration:
            raise ValueError(
                f"settle_time: {self.settle_time} s must be shorter than duration "
                f"({self.duration} s)"
            )
        if self.dt is not None and self.dt > self.sure_unstable_step:
            raise ValueError(
                f"dt: {self.dt} s is past the stability limit {self.sure_unstable_step:.3g} s "
                f"of one spring of the stiffest material between two masses; leave dt out in "
                f"the physical profile (derived from the materials) or lower it"
            )
        steps = self.duration / self.step  # may overflow to inf for a dt near zero
        if not steps <= MAX_STEPS:
            raise ValueError(
                f"duration: duration / dt = {steps:.4g} steps, more than the limit of {MAX_STEPS}"
            )
        return self

    @property
    def critical_step(self) -> float:
        """The largest stable step (s) of any voxel robot of these materials (`step`)."""
        return critical_step(
            max(self.soft_stiffness, self.hard_stiffness, self.actuated_stiffness),
            self.mass,
            self.ground_stiffness,
            max(self.material_damping, self.contact_damping),
        )

    @property
    def sure_unstable_step(self) -> float:
        """A step past which any robot with a spring of the stiffest material blows up
        (`step.sure_unstable_step`): a hand-set dt beyond it is refused."""
        return sure_unstable_step(
            max(self.soft_stiffness, self.hard_stiffness, self.actuated_stiffness),
            self.mass,
            self.material_damping,
        )

    @property
    def step(self) -> float:
        """The time step used (s): `dt`, or `dt_fraction` of the critical step."""
        return self.dt if self.dt is not None else self.dt_fraction * self.critical_step

    @property
    def velocity_factor(self) -> float:
        """What every velocity is multiplied by each step: `damping` (per step, the paper's
        legacy) times exp(-drag dt) (physical: the same decay per second at any dt)."""
        if self.drag == 0.0:
            return self.damping  # the paper's arithmetic, to the last bit
        return self.damping * math.exp(-self.drag * self.step)

    @property
    def n_steps(self) -> int:
        """Number of integration steps: duration / dt, rounded to the nearest integer."""
        return max(1, round(self.duration / self.step))

    @property
    def settle_steps(self) -> int:
        """Step at which the fitness clock starts."""
        return round(self.settle_time / self.step)

    @property
    def measured_time(self) -> float:
        """Seconds between the fitness clock's start and the end of the simulation."""
        return (self.n_steps - self.settle_steps) * self.step


def sim_settings(
    overrides: dict[str, Any] | None = None, base: SimSettings | None = None
) -> SimSettings:
    """Return `base` (default: the defaults of the profile the overrides name, `paper` where
    they name none) with `overrides` applied and validated."""
    merged = base.model_dump() if base is not None else {}
    merged.update(overrides or {})
    return SimSettings.model_validate(merged)


def format_validation_error(error: ValidationError, prefix: str = "") -> str:
    """One line naming every offending field, e.g. `sim.dt: Input should be greater than 0;
    sim.mass: ...`: each problem is listed, none hidden behind a count."""
    return "; ".join(_problem(problem, prefix) for problem in error.errors())


#: Where pydantic puts the chosen kind of a tagged union in an error's location (`sim.terrain.
#: steps.depth`): left out, so the field reads as it is written (`sim.terrain.depth`).
_TAGGED = {"terrain": {"flat", "slope", "steps", "rough", "hurdles"}}


def _problem(problem: Any, prefix: str) -> str:
    parts = [str(part) for part in (prefix, *problem["loc"]) if part != ""]
    parts = [p for i, p in enumerate(parts) if not (i and p in _TAGGED.get(parts[i - 1], ()))]
    message = problem["msg"].removeprefix("Value error, ")
    field, _, rest = message.partition(": ")
    if parts and rest and field.isidentifier():  # a model-level check that names its field
        parts, message = [*parts, field], rest
    if not parts:
        return message
    return f"{'.'.join(parts)}: {message}"
