"""Terrain: contact that could catch a wrong surface, normal or face, against physical
expectations and against the NumPy reference (tests/reference_physics.py), and batching that
stays bit-identical on every terrain."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys

import numpy as np
import pytest
from numba import njit

from softevo.core.physics import simulate, simulate_batch
from softevo.core.robots.robot import Actuation, VoxelRobot, build_mechanics
from softevo.core.robots.settings import SimSettings, sim_settings
from softevo.core.robots.terrain import FIRST_FEATURE_GAP, Rough, sincos
from tests import reference_physics as reference

TERRAINS = {
    "flat": {"kind": "flat"},
    "slope": {"kind": "slope", "angle_deg": 12.0},
    "steps": {"kind": "steps", "height": 0.2, "depth": 0.75},
    "rough": {"kind": "rough", "amplitude": 0.15, "wavelength": 1.5, "seed": 4},
    "hurdles": {"kind": "hurdles", "height": 0.2, "spacing": 1.1, "width": 0.3},
}


def sim(terrain: dict, **overrides: float) -> SimSettings:
    return sim_settings({"duration": 2.0, "settle_time": 0.5, "terrain": terrain, **overrides})


def crawler(terrain: dict, **overrides: float) -> VoxelRobot:
    """A 2x1x1 robot that moves quickly (w = 6): it meets risers, bar faces and the field."""
    settings = sim(terrain, omega=6.0, edge_length=0.5, **overrides)
    return VoxelRobot((3, 1, 1), ("sine", "hard", "neg_sine"), Actuation(0.2, 1.0, 0.5), settings)


def hard_block(terrain: dict, **overrides: float) -> VoxelRobot:
    settings = sim(terrain, duration=4.0, settle_time=2.0, edge_length=0.5, **overrides)
    return VoxelRobot((2, 2, 1), ("hard",) * 4, Actuation(), settings)


@pytest.mark.parametrize("name", list(TERRAINS))
def test_kernel_agrees_with_reference_on_every_terrain(name: str) -> None:
    mech = build_mechanics(crawler(TERRAINS[name]))
    result, _ = simulate(mech)
    expected = reference.run(mech)
    assert result.stable
    assert np.abs(expected.final_positions - mech.positions).max() > 1e-2  # it really moved
    np.testing.assert_allclose(
        result.final_positions, expected.final_positions, rtol=1e-9, atol=1e-9
    )
    assert math.isclose(result.energy, expected.energy, rel_tol=1e-9)


@pytest.mark.parametrize("name", list(TERRAINS))
def test_single_and_batched_runs_are_bit_identical_on_every_terrain(name: str) -> None:
    robots = [crawler(TERRAINS[name]), hard_block(TERRAINS[name]), crawler(TERRAINS[name])]
    robots[2] = dataclasses.replace(robots[2], actuation=Actuation(-0.3, 0.8, 1.9))
    alone = [simulate(robot)[0] for robot in robots]
    for threads, lanes in ((1, 8), (2, 1)):
        batched = simulate_batch(robots, threads=threads, lanes=lanes, energy=True)
        for one, many in zip(alone, batched, strict=True):
            assert one.final_positions.tobytes() == many.final_positions.tobytes()
            assert (one.speed, one.forward_speed, one.climb_rate, one.energy) == (
                many.speed,
                many.forward_speed,
                many.climb_rate,
                many.energy,
            )


def test_the_robot_starts_drop_height_above_the_terrain_beneath_it() -> None:
    for terrain in TERRAINS.values():
        robot = crawler(terrain, drop_height=0.05)
        positions = build_mechanics(robot).positions
        ground = robot.sim.terrain.surface(positions[:, 0], positions[:, 1])
        assert (positions[:, 2] - ground).min() == pytest.approx(0.05, abs=1e-12)


def test_a_hard_block_on_a_slope_below_the_friction_angle_stays_put() -> None:
    angle = math.degrees(math.atan(0.6)) - 8.0  # mu = 0.6: the friction angle is 30.96 degrees
    result, _ = simulate(hard_block({"kind": "slope", "angle_deg": angle}))
    assert result.stable
    assert result.speed < 2e-3


def test_a_hard_block_on_a_slope_above_the_friction_angle_slides_down() -> None:
    angle = math.degrees(math.atan(0.6)) + 8.0
    result, _ = simulate(hard_block({"kind": "slope", "angle_deg": angle}))
    assert result.stable
    assert result.forward_speed < -0.05  # down the slope is -x
    assert result.climb_rate < 0


def test_a_block_dropped_onto_a_step_rests_at_the_steps_height() -> None:
    steps = {"kind": "steps", "height": 0.3, "depth": 2.0}
    mech = build_mechanics(hard_block(steps))
    rear = mech.positions[:, 0].min()
    on_step = mech.positions + np.array([2.4 - rear, 0.0, 0.3 + 0.2])  # x in [2.4, 3.4]: step 1
    result, _ = simulate(dataclasses.replace(mech, positions=on_step))
    lowest = result.final_positions[:, 2].min()
    assert lowest == pytest.approx(0.3, abs=2e-3)  # the penalty spring sinks it ~1e-4 m
    assert result.speed < 1e-3


def test_a_block_caught_in_a_riser_is_pushed_back_by_its_face() -> None:
    """A block whose front sits 2 cm inside a riser 0.8 m high: the nearest face is the riser,
    so it is pushed back along -x (a wrong normal would lift it onto the step)."""
    steps = {"kind": "steps", "height": 0.8, "depth": 2.0}
    mech = build_mechanics(hard_block(steps))
    front = mech.positions[:, 0].max()
    assert front == pytest.approx(2.0 - FIRST_FEATURE_GAP)  # on the ground of step 0
    inside = np.array([2.02 - front, 0.0, 0.0])
    caught = dataclasses.replace(mech, positions=mech.positions + inside)
    result, _ = simulate(caught)
    assert result.stable
    assert result.final_positions[:, 0].max() < 2.0 + 1e-3
    assert result.final_positions[:, 0].max() > 1.9  # pushed out, not flung
    assert result.final_positions[:, 2].min() < 0.05  # still on the lower ground


def test_a_rough_field_is_the_same_for_the_same_seed_in_another_process() -> None:
    terrain = Rough(amplitude=0.2, wavelength=2.0, seed=11)
    grid = np.linspace(-5.0, 5.0, 41)
    here = terrain.surface(grid[:, None], grid[None, :])
    code = (
        "import numpy as np, sys; from softevo.core.robots.terrain import Rough; "
        "g = np.linspace(-5.0, 5.0, 41); "
        "sys.stdout.write(Rough(amplitude=0.2, wavelength=2.0, seed=11)"
        ".surface(g[:, None], g[None, :]).tobytes().hex())"
    )
    there = subprocess.run(
        [sys.executable, "-P", "-c", code], capture_output=True, text=True, check=True, timeout=60
    ).stdout
    assert bytes.fromhex(there) == here.tobytes()
    assert np.abs(here).max() <= 0.2 and np.abs(here).max() > 0.05  # a field, not a plane
    other = Rough(amplitude=0.2, wavelength=2.0, seed=12).surface(grid[:, None], grid[None, :])
    assert not np.array_equal(here, other)


def test_the_fields_sine_and_cosine_are_within_two_ulp_and_the_same_bits_compiled() -> None:
    angles = np.concatenate([np.linspace(-300.0, 300.0, 200_001), [0.0, math.pi / 4, -math.pi]])
    sin_a, cos_a = sincos(angles)
    for got, true in ((sin_a, np.sin(angles)), (cos_a, np.cos(angles))):
        assert (np.abs(got - true) <= 2 * np.spacing(np.abs(true)) + 1e-20).all()  # 0s: absolute
    compiled = njit(sincos)
    for angle in angles[::997]:  # the kernels' scalar path gives NumPy's bits
        assert compiled(angle) == (sin_a[angles == angle][0], cos_a[angles == angle][0])
    # A golden value: the field's arithmetic is IEEE only, so every machine gives these bits.
    height = Rough(amplitude=0.2, wavelength=2.0, seed=11).surface(1.3, -0.7)
    assert float(height) == float.fromhex("0x1.d9284fe66ad4ap-4")


def test_flat_by_default_and_named_flat_are_the_same_simulation() -> None:
    named = crawler({"kind": "flat"})
    plain = sim_settings({"duration": 2.0, "settle_time": 0.5, "omega": 6.0, "edge_length": 0.5})
    default = dataclasses.replace(named, sim=plain)
    assert default.sim == named.sim
    first, second = simulate(default)[0], simulate(named)[0]
    assert first.final_positions.tobytes() == second.final_positions.tobytes()


def test_an_unknown_terrain_is_refused_with_the_kinds_it_could_be() -> None:
    from softevo.core.robots.robot_file import RobotFileError, parse_robot, robot_to_json

    document = robot_to_json(crawler({"kind": "flat"}))
    document["sim"]["terrain"] = {"kind": "stairs", "height": 1}
    with pytest.raises(RobotFileError, match=r"sim\.terrain.*steps"):
        parse_robot(document)
    document["sim"]["terrain"] = {"kind": "steps", "height": -1, "depth": 1}
    with pytest.raises(RobotFileError, match=r"sim\.terrain\.height"):
        parse_robot(document)
