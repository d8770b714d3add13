"""The kernels against the NumPy reference (tests/reference_physics.py) in the physical profile:
the step derived from the materials, drag as exp(-drag dt), the springs' dashpots on the change
of their length and the ground's dashpot in contact, alone and batched, flat and on terrain.

Bound: rtol 1e-9 and atol 1e-10 m on positions, as in test_physics.py: the two evaluate the same
equations in float64 in different orders, and the damping keeps the rounding from growing
(measured: 5e-15 .. 7e-15 m)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from softevo.core.physics import simulate, simulate_batch
from softevo.core.robots.robot import Actuation, VoxelRobot, build_mechanics
from softevo.core.robots.settings import sim_settings
from tests import reference_physics as reference

RTOL = 1e-9
ATOL = 1e-10  # m
TERRAINS = {
    "flat": {"kind": "flat"},
    "slope": {"kind": "slope", "angle_deg": 12.0},
    "rough": {"kind": "rough", "amplitude": 0.15, "wavelength": 1.5, "seed": 4},
}


GENES = Actuation(0.2, 1.0, 0.5)


def physical_crawler(terrain: dict, genes: Actuation = GENES) -> VoxelRobot:
    """A 3x1x1 crawler (w = 6) dropped 5 cm: its springs' and the ground's dashpots both work."""
    sim = sim_settings(
        {
            "profile": "physical",
            "duration": 1.5,
            "settle_time": 0.5,
            "omega": 6.0,
            "edge_length": 0.5,
            "drop_height": 0.05,
            "terrain": terrain,
        }
    )
    return VoxelRobot((3, 1, 1), ("sine", "hard", "neg_sine"), genes, sim)


def test_the_physical_profile_exercises_every_new_term() -> None:
    sim = physical_crawler(TERRAINS["flat"]).sim
    assert sim.dt is None and sim.step < 0.0005  # derived from the materials
    assert sim.velocity_factor < 1.0 and sim.damping == 1.0  # drag, not the legacy factor
    assert sim.material_damping > 0 and sim.contact_damping > 0


@pytest.mark.parametrize("name", list(TERRAINS))
def test_kernel_agrees_with_the_reference_in_the_physical_profile(name: str) -> None:
    mech = build_mechanics(physical_crawler(TERRAINS[name]))
    result, _ = simulate(mech)
    expected = reference.run(mech)
    assert result.stable
    assert np.abs(expected.final_positions - mech.positions).max() > 1e-2  # it really moved
    np.testing.assert_allclose(result.final_positions, expected.final_positions, RTOL, ATOL)
    np.testing.assert_allclose(result.com_start, expected.settle_positions.mean(axis=0), RTOL, ATOL)
    assert result.energy == pytest.approx(expected.energy, rel=1e-9)


@pytest.mark.parametrize("name", ["flat", "slope"])
def test_batched_physical_robots_agree_with_the_reference_and_with_one_at_a_time(
    name: str,
) -> None:
    robots = [physical_crawler(TERRAINS[name]), physical_crawler(TERRAINS[name])]
    robots[1] = dataclasses.replace(robots[1], actuation=Actuation(-0.3, 0.8, 1.9))
    batched = simulate_batch(robots, lanes=8)
    for robot, many in zip(robots, batched, strict=True):
        one, _ = simulate(robot, energy=False)
        assert one.final_positions.tobytes() == many.final_positions.tobytes()
        expected = reference.run(build_mechanics(robot))
        np.testing.assert_allclose(many.final_positions, expected.final_positions, RTOL, ATOL)


def test_each_damping_term_changes_the_motion() -> None:
    """Each term the reference adds matters: switched off one at a time, the robot ends
    elsewhere (so agreement above is not agreement on terms that do nothing)."""
    robot = physical_crawler(TERRAINS["flat"])
    base = simulate(robot)[0].final_positions
    for term in ("drag", "material_damping", "contact_damping"):
        sim = sim_settings({term: 0.0, "dt": robot.sim.step}, base=robot.sim)
        moved = simulate(dataclasses.replace(robot, sim=sim))[0].final_positions
        assert np.abs(moved - base).max() > 1e-4, term
