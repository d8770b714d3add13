"""The step from the material (issue 49): derived in the physical profile, so a stiff material
or a light mass runs at a stable step instead of blowing up; a hand-set dt past the stability
limit of the stiffest spring refused in one line naming `sim.dt`."""

from __future__ import annotations

import math

import pytest

from softevo.core.config import ConfigError, resolve
from softevo.core.physics import simulate
from softevo.core.robots.robot import Actuation, VoxelRobot
from softevo.core.robots.settings import SimSettings, sim_settings
from softevo.core.robots.step import SPRINGS_AT_A_POINT, critical_step, damped_limit

STIFF = {"hard_stiffness": 2e6, "actuated_stiffness": 2e6, "duration": 1.0, "settle_time": 0.2}


def test_the_critical_step_is_gershgorins_bound_with_the_damping_limit() -> None:
    sim = sim_settings({"profile": "physical"})
    omega = math.sqrt((2 * SPRINGS_AT_A_POINT * 2000.0 + 1e4) / 0.1)
    assert sim.critical_step == pytest.approx(damped_limit(1.0) / omega, rel=1e-12)
    assert sim.step == pytest.approx(0.8 * sim.critical_step, rel=1e-12)
    assert damped_limit(0.0) == 2.0 and damped_limit(1.0) == pytest.approx(0.8284, abs=1e-4)


def test_a_stiffer_material_or_a_lighter_mass_gets_a_smaller_step() -> None:
    base = sim_settings({"profile": "physical"}).step
    assert sim_settings({"profile": "physical", "hard_stiffness": 8000.0}).step < base
    assert sim_settings({"profile": "physical", "mass": 0.01}).step < base
    assert critical_step(0.0, 1.0, 0.0, 0.0) == math.inf


def test_a_stiff_robot_runs_stable_at_the_derived_step() -> None:
    sim = sim_settings({"profile": "physical", **STIFF})
    robot = VoxelRobot((2, 1, 1), ("hard", "sine"), Actuation(0.0, 1.0, 0.0), sim)
    result, _ = simulate(robot)
    assert result.stable and math.isfinite(result.speed)


def test_a_hand_set_step_past_the_limit_is_refused_naming_sim_dt() -> None:
    with pytest.raises(ConfigError, match=r"^sim\.dt: 0\.0005 s is past the stability limit"):
        resolve({"preset": "paper-voxel", "sim": STIFF})
    SimSettings.model_validate({"dt": 0.0005})  # the paper's own numbers pass


def test_a_hand_set_step_still_wins_over_the_derived_one() -> None:
    assert sim_settings({"profile": "physical", "dt": 0.0002}).step == 0.0002
    assert resolve({"preset": "quick", "sim": {"dt": 0.0002}}).sim.step == 0.0002
