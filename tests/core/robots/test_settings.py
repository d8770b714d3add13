"""Simulation settings: the paper's defaults, and bad values refused with the field named."""

from __future__ import annotations

import math

import pytest
from pydantic import ValidationError

from softevo.core.robots.settings import SimSettings, format_validation_error, sim_settings


def test_defaults_follow_the_paper() -> None:
    sim = SimSettings()
    assert (sim.dt, sim.gravity, sim.damping, sim.ground_stiffness) == (0.0005, -9.81, 0.99, 1e4)
    assert (sim.friction, sim.mass, sim.soft_stiffness, sim.hard_stiffness) == (0.6, 0.1, 500, 2000)
    assert sim.n_steps == 20_000 and sim.settle_steps == 2_000
    assert sim.measured_time == pytest.approx(9.0)


def test_step_counts_round_to_the_nearest_step() -> None:
    sim = sim_settings({"dt": 0.001, "duration": 0.0994, "settle_time": 0.0496})
    assert sim.n_steps == 99 and sim.settle_steps == 50
    assert sim.measured_time == pytest.approx(0.049)


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        ({"dt": 0.0}, "dt"),
        ({"dt": -0.001}, "dt"),
        ({"dt": math.nan}, "dt"),
        ({"dt": math.inf}, "dt"),
        ({"duration": 0.0}, "duration"),
        ({"duration": -1.0}, "duration"),
        ({"duration": math.nan}, "duration"),
        ({"damping": 1.5}, "damping"),
        ({"damping": math.nan}, "damping"),
        ({"friction": -0.1}, "friction"),
        ({"mass": 0.0}, "mass"),
        ({"dt": "0.001"}, "dt"),  # strict: no strings
        ({"warp_drive": 1.0}, "warp_drive"),
        ({"settle_time": 10.0}, "settle_time"),  # == duration
        ({"settle_time": 12.0}, "settle_time"),
        ({"settle_time": -1.0}, "settle_time"),
        ({"dt": 1e-6, "duration": 3600.0}, "duration"),  # too many steps
    ],
)
def test_bad_settings_are_refused_naming_the_field(overrides: dict, field: str) -> None:
    with pytest.raises(ValidationError) as info:
        sim_settings(overrides)
    message = format_validation_error(info.value)
    assert message.startswith(f"{field}: "), message
    assert "\n" not in message
    # Under a prefix the field is still named; model-level checks (settle_time, step count) come
    # out as "sim: settle_time: ..." rather than "sim.settle_time: ...".
    prefixed = format_validation_error(info.value, prefix="sim")
    assert prefixed.startswith((f"sim.{field}: ", f"sim: {field}: ")), prefixed


def test_settings_are_frozen() -> None:
    sim = SimSettings()
    with pytest.raises(ValidationError):
        sim.dt = 0.001  # type: ignore[misc]


def test_overrides_apply_on_a_base() -> None:
    base = sim_settings({"duration": 3.0})
    sim = sim_settings({"friction": 0.9}, base=base)
    assert (sim.duration, sim.friction, sim.dt) == (3.0, 0.9, 0.0005)
