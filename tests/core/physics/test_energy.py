"""Actuator work, `energy`: a closed-form case, the reference, and what it must not change."""

from __future__ import annotations

import math

import numpy as np
import pytest

from softevo.core.physics import kernels, simulate, simulate_batch
from softevo.core.robots.robot import Actuation, VoxelRobot, build_mechanics
from softevo.core.robots.settings import sim_settings
from softevo.core.robots.terrain import kernel_params
from tests import reference_physics as reference


def test_a_pinned_spring_driven_sinusoidally_does_the_closed_form_work() -> None:
    """Two masses that cannot move, joined by a spring at its rest length whose actuator drives
    L0 = L + a sin(w t): the tension is T = -k a sin(w t) and the actuator's power
    |T dL0/dt| = k a^2 w |sin(w t) cos(w t)|, so over whole periods the work is k a^2 w T / pi."""
    k, length, a, omega = 2000.0, 1.0, 0.05, 2.0 * math.pi
    dt, duration, settle = 1e-4, 3.0, 1.0  # the work is counted from the settle step on
    steps, settle_step = round(duration / dt), round(settle / dt)
    x, y, z = np.array([0.0, length]), np.zeros(2), np.full(2, 1.0)
    zeros = np.zeros(2)
    work = np.zeros(1)
    kind, params = kernel_params(sim_settings().terrain)
    kernels.simulate_one(
        x,
        y,
        z,
        zeros.copy(),
        zeros.copy(),
        zeros.copy(),
        np.zeros(2),  # pinned: step factor 0
        np.array([0]),
        np.array([1]),
        np.array([k]),
        np.array([length]),
        np.array([a]),
        np.array([0.0]),
        np.zeros(0),
        omega,
        dt,
        steps,
        -0.981,
        1e4,
        0.0,
        0.6,
        0.99,
        kind,
        params,
        settle_step,
        np.empty(2),
        np.empty(2),
        np.empty(2),
        0,
        np.empty((0, 3, 2)),
        work,
    )
    expected = k * a * a * omega * (duration - settle) / math.pi
    assert work[0] == pytest.approx(expected, rel=1e-3)


def test_energy_agrees_with_the_reference_and_is_the_same_batched() -> None:
    settings = sim_settings({"duration": 2.0, "settle_time": 0.5, "omega": 5.0})
    robot = VoxelRobot(
        (2, 2, 1), ("sine", "neg_sine", "hard", "soft"), Actuation(0.1, 1.0, 0.3), settings
    )
    mech = build_mechanics(robot)
    alone, _ = simulate(mech)
    assert alone.energy > 1.0
    assert alone.energy == pytest.approx(reference.run(mech).energy, rel=1e-9)
    batched = simulate_batch([robot, robot], energy=True)
    assert [r.energy for r in batched] == [alone.energy, alone.energy]
    assert simulate_batch([robot])[0].energy != simulate_batch([robot])[0].energy  # NaN: not asked


def test_measuring_energy_changes_no_position_and_a_passive_robot_does_no_work() -> None:
    settings = sim_settings({"duration": 1.0, "settle_time": 0.2, "omega": 5.0})
    robot = VoxelRobot((2, 1, 1), ("sine", "hard"), Actuation(0.1, 1.0, 0.3), settings)
    measured, plain = simulate_batch([robot], energy=True)[0], simulate_batch([robot])[0]
    assert measured.final_positions.tobytes() == plain.final_positions.tobytes()
    passive = VoxelRobot((2, 1, 1), ("hard", "soft"), Actuation(), settings)
    result, _ = simulate(passive)
    assert result.energy == 0.0
    assert result.efficiency == 0.0 and not result.cost_of_transport > 0  # 0, or NaN at rest


def test_cost_of_transport_and_efficiency_follow_from_energy_and_distance() -> None:
    settings = sim_settings({"duration": 3.0, "settle_time": 0.5, "omega": 6.0})
    robot = VoxelRobot((3, 1, 1), ("sine", "hard", "neg_sine"), Actuation(0.2, 1.0, 0.5), settings)
    result, _ = simulate(robot)
    assert result.distance > 1e-3 and result.energy > 0
    assert result.efficiency == result.distance / result.energy
    mass = build_mechanics(robot).n_masses * settings.mass
    assert result.cost_of_transport == pytest.approx(
        result.energy / (mass * 9.81 * result.distance)
    )
    document = result.to_json()
    for key in ("speed", "forward_speed", "climb_rate", "energy", "cost_of_transport"):
        assert isinstance(document[key], float), key
