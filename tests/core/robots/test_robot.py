"""Robots to mechanics: materials, actuation, the shared-spring rule and refused robots.

The shared-spring rule (core/robots/robot.py, docs/physics.md): a spring shared by voxels is their
springs in parallel, k = sum k_v and L0(t) = sum(k_v L_v(t)) / k.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from softevo.core.robots.lattice import full_lattice
from softevo.core.robots.robot import (
    Actuation,
    LabelledSpringRobot,
    RobotError,
    SpringRobot,
    VoxelRobot,
    build_mechanics,
)
from softevo.core.robots.settings import sim_settings

SIM = sim_settings({"edge_length": 0.5, "drop_height": 0.2, "omega": 3.0})
HARD, SOFT, ACT = SIM.hard_stiffness, SIM.soft_stiffness, SIM.actuated_stiffness
GENES = Actuation(a=0.4, b=1.2, c=0.9)


def spring_index(mech, p: tuple[int, int, int], q: tuple[int, int, int]) -> int:
    """Row of the spring between lattice corners p and q (grid units)."""
    rest = mech.lattice.rest_positions
    i = int(np.flatnonzero((rest == p).all(axis=1))[0])
    j = int(np.flatnonzero((rest == q).all(axis=1))[0])
    row = np.flatnonzero((mech.lattice.springs == sorted((i, j))).all(axis=1))
    assert len(row) == 1, (p, q)
    return int(row[0])


def expected_actuation(weights: list[tuple[float, float, float]], length: float):
    """(k, rest, amp_sin, amp_cos) of a spring of grid length `length` shared by voxels given as
    (k_v, relative offset, signed relative amplitude)."""
    k = sum(w for w, _, _ in weights)
    offset = sum(w * o for w, o, _ in weights) / k
    amplitude = sum(w * a for w, _, a in weights) / k
    metres = length * SIM.edge_length
    return (
        k,
        metres * (1 + offset),
        metres * amplitude * math.cos(GENES.c),
        metres * amplitude * math.sin(GENES.c),
    )


def spring_params(mech, row: int) -> tuple[float, float, float, float]:
    return (
        mech.stiffness[row],
        mech.rest_length[row],
        mech.amp_sin[row],
        mech.amp_cos[row],
    )


HARD_V = (HARD, 0.0, 0.0)
SOFT_V = (SOFT, 0.0, 0.0)
SINE_V = (ACT, SIM.offset_scale * GENES.a, SIM.amplitude_scale * GENES.b)
NEG_V = (ACT, SIM.offset_scale * GENES.a, -SIM.amplitude_scale * GENES.b)


def test_hard_soft_bar_shared_face_is_the_sum() -> None:
    mech = build_mechanics(VoxelRobot((2, 1, 1), ("hard", "soft"), GENES, SIM))
    shared_edge = spring_index(mech, (1, 0, 0), (1, 1, 0))
    shared_diagonal = spring_index(mech, (1, 0, 0), (1, 1, 1))
    assert mech.stiffness[shared_edge] == HARD + SOFT == 2500.0
    assert mech.stiffness[shared_diagonal] == HARD + SOFT
    assert mech.rest_length[shared_edge] == pytest.approx(0.5, rel=1e-15)
    assert mech.rest_length[shared_diagonal] == pytest.approx(0.5 * math.sqrt(2), rel=1e-15)
    # Unshared springs keep their own voxel's stiffness.
    assert mech.stiffness[spring_index(mech, (0, 0, 0), (0, 1, 0))] == HARD
    assert mech.stiffness[spring_index(mech, (0, 0, 0), (1, 0, 0))] == HARD
    assert mech.stiffness[spring_index(mech, (0, 0, 0), (1, 1, 1))] == HARD
    assert mech.stiffness[spring_index(mech, (2, 0, 0), (2, 1, 1))] == SOFT
    assert mech.stiffness[spring_index(mech, (1, 0, 0), (2, 1, 1))] == SOFT
    # In all: 6 shared springs, 22 of each voxel alone.
    assert sorted(np.unique(mech.stiffness, return_counts=True)[1].tolist()) == [6, 22, 22]
    assert not mech.amp_sin.any() and not mech.amp_cos.any()
    assert mech.omega == 0.0  # nothing actuated


def test_sine_hard_bar_shares_amplitude_by_stiffness() -> None:
    mech = build_mechanics(VoxelRobot((2, 1, 1), ("sine", "hard"), GENES, SIM))
    assert mech.omega == SIM.omega
    cases = [
        ((1, 0, 0), (1, 0, 1), [SINE_V, HARD_V], 1.0),  # shared edge: half the amplitude
        ((1, 0, 0), (1, 1, 1), [SINE_V, HARD_V], math.sqrt(2)),  # shared face diagonal
        ((0, 0, 0), (0, 1, 0), [SINE_V], 1.0),  # sine voxel alone
        ((0, 0, 0), (1, 1, 1), [SINE_V], math.sqrt(3)),
        ((1, 0, 0), (2, 1, 1), [HARD_V], math.sqrt(3)),  # hard voxel alone
    ]
    for p, q, weights, length in cases:
        got = spring_params(mech, spring_index(mech, p, q))
        np.testing.assert_allclose(
            got, expected_actuation(weights, length), rtol=1e-14, err_msg=f"{p}-{q}"
        )
    shared = spring_params(mech, spring_index(mech, (1, 0, 0), (1, 0, 1)))
    alone = spring_params(mech, spring_index(mech, (0, 0, 0), (0, 0, 1)))
    assert shared[2] == pytest.approx(alone[2] * ACT / (ACT + HARD))  # = half, as k_sine = k_hard
    assert shared[2] == pytest.approx(alone[2] / 2)


def test_edge_shared_by_four_voxels() -> None:
    """The vertical edge at the centre of a 2x2x1 block belongs to all four voxels."""
    labels = ("hard", "soft", "sine", "neg_sine")
    mech = build_mechanics(VoxelRobot((2, 2, 1), labels, GENES, SIM))
    row = spring_index(mech, (1, 1, 0), (1, 1, 1))
    expected = expected_actuation([HARD_V, SOFT_V, SINE_V, NEG_V], 1.0)
    np.testing.assert_allclose(spring_params(mech, row), expected, rtol=1e-14, atol=1e-17)
    assert mech.stiffness[row] == HARD + SOFT + 2 * ACT
    assert mech.amp_sin[row] == pytest.approx(0.0, abs=1e-15)  # sine and neg_sine cancel
    # The face between sine and neg_sine (x = 1, y from 1 to 2): amplitudes cancel, offsets add.
    face = spring_index(mech, (1, 1, 0), (1, 2, 1))
    np.testing.assert_allclose(
        spring_params(mech, face), expected_actuation([SINE_V, NEG_V], math.sqrt(2)), atol=1e-15
    )


def test_empty_voxels_add_nothing() -> None:
    mech = build_mechanics(VoxelRobot((2, 1, 1), ("hard", "empty"), GENES, SIM))
    assert mech.n_masses == 8 and mech.n_springs == 28
    assert (mech.stiffness == HARD).all()


def test_initial_positions_scale_with_edge_length_and_sit_at_drop_height() -> None:
    mech = build_mechanics(VoxelRobot((2, 1, 1), ("hard", "soft"), GENES, SIM))
    assert mech.positions[:, 2].min() == pytest.approx(SIM.drop_height)
    np.testing.assert_allclose(
        mech.positions - [0, 0, SIM.drop_height], mech.lattice.rest_positions * SIM.edge_length
    )


def test_disconnected_voxels_are_not_built() -> None:
    # Voxels (0,0,0), (1,1,0), (1,0,1), (0,1,1): every pair shares an edge, none a face.
    labels = ("hard", "empty", "empty", "sine", "empty", "sine", "soft", "empty")
    mech = build_mechanics(VoxelRobot((2, 2, 2), labels, GENES, SIM))
    assert mech.lattice.kept.tolist() == [True] + [False] * 7
    assert mech.n_masses == 8
    assert (mech.stiffness == HARD).all()  # the kept one is voxel 0 (lowest index), hard


def test_voxel_robot_refusals() -> None:
    with pytest.raises(RobotError, match=r"voxels: .*no filled voxel"):
        build_mechanics(VoxelRobot((1, 1, 2), ("empty", "empty"), GENES, SIM))
    with pytest.raises(RobotError, match="voxels: unknown label 'rubber'"):
        build_mechanics(VoxelRobot((1, 1, 2), ("hard", "rubber"), GENES, SIM))


def paper_options(n: int = 28) -> np.ndarray:
    options = np.array([[1000, 0, 1, 0], [2000, 0, 1, 0], [5000, 0.05, 1, 0], [5000, -0.05, 1, 0]])
    return options[np.arange(n) % 4].astype(np.float64)


def test_spring_robot_uses_each_spring_option() -> None:
    options = paper_options()
    options[:, 3] = np.linspace(-1, 1, 28)
    mech = build_mechanics(SpringRobot((1, 1, 1), (True,), options, SIM))
    length = mech.lattice.spring_lengths * SIM.edge_length
    k, b, _, c = options.T
    np.testing.assert_array_equal(mech.stiffness, k)
    np.testing.assert_allclose(mech.rest_length, length, rtol=1e-15)
    np.testing.assert_allclose(mech.amp_sin, length * b * np.cos(c), rtol=1e-15)
    np.testing.assert_allclose(mech.amp_cos, length * b * np.sin(c), rtol=1e-15)
    assert mech.omega == 1.0  # the springs' own w, not sim.omega


def test_spring_robot_refuses_actuated_springs_with_different_frequencies() -> None:
    options = paper_options()
    options[2, 2] = 2.0  # an actuated spring (b = 0.05) with w = 2
    with pytest.raises(RobotError, match=r"springs: .*one frequency w.*\[1\.0, 2\.0\]"):
        build_mechanics(SpringRobot((1, 1, 1), (True,), options, SIM))


def test_spring_robot_ignores_the_frequency_of_passive_springs() -> None:
    options = paper_options()
    options[0, 2] = 7.0  # b = 0: w has no effect
    assert build_mechanics(SpringRobot((1, 1, 1), (True,), options, SIM)).omega == 1.0


@pytest.mark.parametrize("shape", [(27, 4), (29, 4), (28, 3), (28,)])
def test_spring_robot_refuses_wrong_number_of_entries(shape) -> None:
    options = np.ones(shape)
    with pytest.raises(RobotError, match=r"springs: expected 28 entries of \[k, b, w, c\]"):
        build_mechanics(SpringRobot((1, 1, 1), (True,), options, SIM))


def test_spring_robot_counts_springs_of_the_built_lattice() -> None:
    """A 2x1x1 spring robot needs 50 entries, not 56 (shared face springs are one spring)."""
    build_mechanics(SpringRobot((2, 1, 1), (True, True), paper_options(50), SIM))
    with pytest.raises(RobotError, match="expected 50 entries"):
        build_mechanics(SpringRobot((2, 1, 1), (True, True), paper_options(56), SIM))


def test_labelled_spring_robot_does_not_merge_shared_springs() -> None:
    n = full_lattice((2, 1, 1)).n_springs
    robot = LabelledSpringRobot((2, 1, 1), (True, True), ("soft",) * n, GENES, SIM)
    mech = build_mechanics(robot)
    assert (mech.stiffness == SOFT).all()  # a shared face spring is one module, not two
    with pytest.raises(RobotError, match="spring_labels: expected 50 labels"):
        build_mechanics(LabelledSpringRobot((2, 1, 1), (True, True), ("soft",) * 49, GENES, SIM))
    with pytest.raises(RobotError, match=r"spring_labels\.3: unknown label 'empty'"):
        labels = ("soft",) * 3 + ("empty",) + ("soft",) * (n - 4)
        build_mechanics(LabelledSpringRobot((2, 1, 1), (True, True), labels, GENES, SIM))
