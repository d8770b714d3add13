"""The physics engine: the numba kernels against the NumPy reference (tests/reference_physics.py),
closed-form motions, conservation laws, symmetry, and determinism across processes and batches.

Bounds used here, and why:

* kernel vs reference: rtol 1e-9 and atol 1e-10 m on positions. Both evaluate the same equations
  in float64 but in different orders, so they differ by rounding (1e-16 relative per operation),
  which damping keeps from growing: measured differences are 1e-15 .. 1e-12 m.
* free fall: semi-implicit Euler's displacement after n steps is exactly g dt^2 n(n+1)/2, which is
  g t^2 / 2 plus g dt t / 2; the test asks for the exact sum to rtol 1e-12 and for the result to lie
  between g t^2 / 2 and g t^2 / 2 + g dt t / 2.
* momentum: with no gravity and no ground only spring forces act, and they cancel pairwise, so
  the centre of mass must not move; rounding leaves it within 1e-9 m (measured: 1e-14 m).
* energy: with no damping, gravity or ground, symplectic Euler conserves a perturbed energy; the
  energy measured with central-difference velocities (x[n+1] - x[n-1]) / 2 dt fluctuates by
  O((h w)^2) and does not drift. Measured: 0.45 % (1x1x1) and 0.28 % (2x1x1) of the stored energy
  at dt = 0.5 ms, a quarter of that at dt / 2; the test allows 1 %, no drift beyond 1e-4 between
  the first and last 1000 steps, and asks that halving dt cut the fluctuation at least threefold.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import io
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from softevo.core.physics import simulate, simulate_batch
from softevo.core.robots.lattice import full_lattice
from softevo.core.robots.robot import (
    SPRING_LABELS,
    Actuation,
    LabelledSpringRobot,
    Mechanics,
    SpringRobot,
    VoxelRobot,
    build_mechanics,
)
from softevo.core.robots.settings import SimSettings, sim_settings
from tests import reference_physics as reference
from tests.conftest import ROOT

RTOL = 1e-9
ATOL = 1e-10  # m
#: The paper's four phase 2 spring options [k, b, w, c].
PAPER_OPTIONS = np.array(
    [[1000, 0, 1, 0], [2000, 0, 1, 0], [5000, 0.05, 1, 0], [5000, -0.05, 1, 0]], dtype=np.float64
)


def short(**overrides: float) -> SimSettings:
    """A 2 s simulation (4000 steps) that settles after 0.5 s, with `overrides`."""
    return sim_settings({"duration": 2.0, "settle_time": 0.5, **overrides})


def rotated(mech: Mechanics, angles: tuple[float, float], lowest: float) -> Mechanics:
    """`mech` turned about x then y through its centre, its lowest point at height `lowest`."""
    ax, ay = angles
    rot_x = np.array([[1, 0, 0], [0, np.cos(ax), -np.sin(ax)], [0, np.sin(ax), np.cos(ax)]])
    rot_y = np.array([[np.cos(ay), 0, np.sin(ay)], [0, 1, 0], [-np.sin(ay), 0, np.cos(ay)]])
    centred = mech.positions - mech.positions.mean(axis=0)
    positions = centred @ rot_x.T @ rot_y.T
    positions[:, 2] += lowest - positions[:, 2].min()
    return dataclasses.replace(mech, positions=positions)


def breathing_cube() -> Mechanics:
    return build_mechanics(VoxelRobot((1, 1, 1), ("sine",), Actuation(0.3, 1.2, 0.7), short()))


def passive_bar() -> Mechanics:
    return build_mechanics(VoxelRobot((2, 1, 1), ("hard", "soft"), Actuation(), short()))


def mixed_voxels() -> Mechanics:
    labels = ("empty", "sine", "neg_sine", "neg_sine", "soft", "soft")
    labels += ("neg_sine", "neg_sine", "soft", "hard", "neg_sine", "hard")
    sim = short(omega=6.0, edge_length=0.5)
    return build_mechanics(VoxelRobot((3, 2, 2), labels, Actuation(-0.5, 1.0, 2.0), sim))


def paper_spring_cube() -> Mechanics:
    options = PAPER_OPTIONS[np.random.default_rng(1).integers(0, 4, 28)]
    return build_mechanics(SpringRobot((1, 1, 1), (True,), options, short()))


def fast_spring_cube() -> Mechanics:
    """Per-spring options with a faster shared w and phases, so actuation visibly matters."""
    rng = np.random.default_rng(2)
    options = PAPER_OPTIONS[rng.integers(0, 4, 28)].copy()
    options[:, 1] *= 2.0
    options[:, 2] = 8.0
    options[:, 3] = rng.uniform(-np.pi, np.pi, 28)
    return build_mechanics(SpringRobot((1, 1, 1), (True,), options, short()))


def labelled_springs() -> Mechanics:
    n = full_lattice((2, 1, 1)).n_springs
    labels = tuple(SPRING_LABELS[i] for i in np.random.default_rng(3).integers(0, 4, n))
    robot = LabelledSpringRobot((2, 1, 1), (True, True), labels, Actuation(0.2, 1.0, 0.5), short())
    return build_mechanics(robot)


def dropped_tilted_bar() -> Mechanics:
    """Dropped 0.3 m onto a corner: ground contact, bouncing, sliding and sticking friction.

    Damping 0.999, not 1.0: undamped bouncing amplifies rounding differences (measured 6e-11 m
    after 3000 steps at 1.0, 2e-12 m at 0.999), which would leave little margin under 1e-9.
    """
    sim = short(drop_height=0.3, damping=0.999, duration=1.5)
    mech = build_mechanics(VoxelRobot((2, 1, 1), ("sine", "hard"), Actuation(0.2, 1.0, 0.5), sim))
    return rotated(mech, (0.4, 0.3), lowest=0.3)


ROBOTS = {
    "breathing_cube": breathing_cube,
    "passive_bar": passive_bar,
    "mixed_voxels": mixed_voxels,
    "paper_spring_cube": paper_spring_cube,
    "fast_spring_cube": fast_spring_cube,
    "labelled_springs": labelled_springs,
    "dropped_tilted_bar": dropped_tilted_bar,
}


@pytest.mark.parametrize("name", list(ROBOTS))
def test_kernel_agrees_with_reference(name: str) -> None:
    mech = ROBOTS[name]()
    result, _ = simulate(mech)
    expected = reference.run(mech)
    assert result.stable
    # The robot must really move, or agreement would say little.
    assert np.abs(expected.final_positions - mech.positions).max() > 1e-3
    np.testing.assert_allclose(result.final_positions, expected.final_positions, RTOL, ATOL)
    np.testing.assert_allclose(result.com_start, expected.settle_positions.mean(axis=0), RTOL, ATOL)
    np.testing.assert_allclose(result.com_end, expected.final_positions.mean(axis=0), RTOL, ATOL)


def test_dropped_robot_touches_the_ground_and_slides() -> None:
    """The drop case exercises the ground and friction terms, not only free flight."""
    mech = dropped_tilted_bar()
    frames = reference.run(mech, record_every=10).frames
    assert frames[:, :, 2].min() < 0  # penetrates the penalty ground
    assert np.abs(frames[-1, :, :2] - frames[0, :, :2]).max() > 0.01  # moves sideways


def test_trajectory_frames_agree_with_reference() -> None:
    mech = mixed_voxels()
    _, trajectory = simulate(mech, record_every=250)
    expected = reference.run(mech, record_every=250)
    assert trajectory is not None
    np.testing.assert_array_equal(trajectory.times, expected.frame_steps * mech.sim.dt)
    np.testing.assert_allclose(trajectory.frames, expected.frames, RTOL, ATOL)


def free_fall_cube(damping: float) -> Mechanics:
    sim = sim_settings(
        {"drop_height": 100.0, "damping": damping, "duration": 1.0, "settle_time": 0.5}
    )
    return build_mechanics(VoxelRobot((1, 1, 1), ("hard",), Actuation(), sim))


def test_free_fall_matches_semi_implicit_euler() -> None:
    mech = free_fall_cube(damping=1.0)
    sim = mech.sim
    result, _ = simulate(mech)
    g, dt = -sim.gravity, sim.dt
    for n, com in ((sim.settle_steps, result.com_start), (sim.n_steps, result.com_end)):
        fallen = mech.positions[:, 2].mean() - com[2]
        exact = g * dt**2 * n * (n + 1) / 2  # v_k = k g dt, x_n = dt * sum v_k
        np.testing.assert_allclose(fallen, exact, rtol=1e-12)
        t = n * dt
        assert g * t**2 / 2 <= fallen <= g * t**2 / 2 + g * dt * t / 2 + 1e-12
    displacement = result.final_positions - mech.positions
    assert np.abs(displacement[:, :2]).max() < 1e-12  # nothing pushes sideways
    np.testing.assert_allclose(displacement[:, 2], displacement[0, 2], rtol=1e-12)  # rigid
    assert result.final_positions[:, 2].min() > 90  # never near the ground


def test_damping_is_applied_once_per_step() -> None:
    """v[n+1] = d (v[n] + g dt): v[n] = v* (1 - d^n) with v* = g dt d / (1 - d)."""
    mech = free_fall_cube(damping=0.99)
    sim = mech.sim
    result, _ = simulate(mech)
    g, dt, d, n = -sim.gravity, sim.dt, sim.damping, sim.n_steps
    terminal = g * dt * d / (1 - d)
    assert terminal == pytest.approx(0.4856, abs=1e-4)  # docs/physics.md
    fallen = dt * terminal * sum(1 - d**k for k in range(1, n + 1))
    np.testing.assert_allclose(mech.positions[0, 2] - result.final_positions[0, 2], fallen, 1e-12)


def weightless(robot: VoxelRobot | SpringRobot) -> VoxelRobot | SpringRobot:
    sim = sim_settings({"gravity": 0.0, "ground_stiffness": 0.0, "damping": 1.0}, base=robot.sim)
    return dataclasses.replace(robot, sim=sim)


def test_actuated_robot_in_space_keeps_its_centre_of_mass() -> None:
    labels = ("sine", "neg_sine", "hard", "sine", "soft", "neg_sine")
    sim = sim_settings({"duration": 2.0, "settle_time": 0.5, "drop_height": 5.0, "omega": 5.0})
    robot = weightless(VoxelRobot((3, 2, 1), labels, Actuation(0.4, 1.5, 1.0), sim))
    mech = build_mechanics(robot)
    result, trajectory = simulate(mech, record_every=50)
    assert trajectory is not None
    start = mech.positions.mean(axis=0)
    assert np.abs(trajectory.frames - mech.positions).max() > 0.05  # the body does deform
    com = trajectory.frames.mean(axis=1)
    assert np.abs(com - start).max() < 1e-9
    assert np.abs(np.array(result.com_end) - start).max() < 1e-9


def stretched_in_space(
    shape: tuple[int, int, int], labels: tuple[str, ...], dt: float, duration: float
):
    sim = sim_settings(
        {
            "duration": duration,
            "settle_time": 0.0,
            "drop_height": 10.0,
            "dt": dt,
            "gravity": 0.0,
            "ground_stiffness": 0.0,
            "damping": 1.0,
        }
    )
    mech = build_mechanics(VoxelRobot(shape, labels, Actuation(), sim))
    centre = mech.positions.mean(axis=0)
    noise = np.random.default_rng(0).normal(0.0, 0.01, mech.positions.shape)
    positions = centre + (mech.positions - centre) * [1.05, 0.97, 1.0] + noise
    return dataclasses.replace(mech, positions=positions)


def energy_series(mech: Mechanics) -> tuple[np.ndarray, float]:
    """Energy at steps 1 .. n-1 (central-difference kinetic + spring) and the initial energy."""
    _, trajectory = simulate(mech, record_every=1)
    assert trajectory is not None
    x, dt = trajectory.frames, mech.sim.dt
    v = (x[2:] - x[:-2]) / (2 * dt)
    kinetic = 0.5 * mech.sim.mass * np.sum(v * v, axis=(1, 2))
    elastic = np.array([reference.spring_energy(mech, frame) for frame in x[1:-1]])
    return kinetic + elastic, reference.spring_energy(mech, mech.positions)


@pytest.mark.parametrize(
    ("shape", "labels"), [((1, 1, 1), ("hard",)), ((2, 1, 1), ("hard", "soft"))]
)
def test_unactuated_robot_conserves_energy(shape, labels) -> None:
    mech = stretched_in_space(shape, labels, dt=0.0005, duration=2.0)
    energy, initial = energy_series(mech)
    assert initial > 1.0  # J: a real deformation
    deviation = np.abs(energy - initial).max() / initial
    assert deviation < 0.01
    assert abs(energy[-1000:].mean() - energy[:1000].mean()) / initial < 1e-4
    # The fluctuation is the integrator's O(dt^2), not a leak: it shrinks with dt.
    finer, _ = energy_series(stretched_in_space(shape, labels, dt=0.00025, duration=2.0))
    assert np.abs(finer - initial).max() / initial < deviation / 3
    # And the energy does move between kinetic and elastic (the robot really vibrates).
    _, trajectory = simulate(mech, record_every=20)
    elastic = [reference.spring_energy(mech, frame) for frame in trajectory.frames]
    assert min(elastic) < 0.5 * initial


@pytest.mark.parametrize(
    ("drop_height", "damping", "settle_time"),
    [(0.0, 0.99, 1.0), (0.0, 0.999, 1.0), (0.3, 0.99, 2.0)],
)
def test_passive_robot_does_not_crawl(drop_height, damping, settle_time) -> None:
    labels = ("hard", "soft", "hard", "empty", "soft", "hard")  # lopsided, nothing actuated
    # Genes are set but no voxel uses them: they must not move the robot either.
    sim = sim_settings(
        {
            "duration": settle_time + 2.0,
            "settle_time": settle_time,
            "drop_height": drop_height,
            "damping": damping,
        }
    )
    result, _ = simulate(VoxelRobot((3, 2, 1), labels, Actuation(0.5, 1.0, 1.0), sim))
    assert result.stable
    assert result.speed < 1e-3


def test_mirror_symmetric_robot_does_not_drift_sideways() -> None:
    by_x = ("sine", "hard", "neg_sine")
    labels = tuple(
        by_x[x] if (z == 0 or x != 1) else "soft"
        for z in range(2)
        for y in range(2)
        for x in range(3)
    )
    sim = sim_settings({"duration": 4.0, "settle_time": 1.0, "omega": 3.0})
    robot = VoxelRobot((3, 2, 2), labels, Actuation(0.0, 1.5, 0.0), sim)
    mech = build_mechanics(robot)
    result, _ = simulate(mech)
    assert abs(result.com_end[0] - result.com_start[0]) > 0.05  # it does crawl, along x
    centre_y = mech.positions[:, 1].mean()
    assert abs(result.com_end[1] - result.com_start[1]) < 1e-9
    assert abs(result.com_end[1] - centre_y) < 1e-9


DETERMINISM_SCRIPT = textwrap.dedent(
    """
    import hashlib
    from softevo.core.physics import simulate
    from softevo.core.robots.robot import Actuation, VoxelRobot
    from softevo.core.robots.settings import SimSettings, sim_settings

    sim = sim_settings({"duration": 1.0, "settle_time": 0.25, "omega": 4.0})
    labels = ("sine", "neg_sine", "hard", "soft", "sine", "empty", "hard", "neg_sine")
    result, _ = simulate(VoxelRobot((2, 2, 2), labels, Actuation(0.3, 1.1, -0.7), sim))
    print(hashlib.sha256(result.final_positions.tobytes()).hexdigest(), repr(result.com_start))
    """
)


def determinism_output_here() -> str:
    """What the script prints when run in this process."""
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        exec(DETERMINISM_SCRIPT, {})
    return buffer.getvalue().strip()


@pytest.mark.slow
def test_same_input_gives_bit_identical_output_in_two_processes() -> None:
    outputs = [
        subprocess.run(
            [sys.executable, "-c", DETERMINISM_SCRIPT],
            capture_output=True,
            text=True,
            check=True,
            cwd=ROOT,
            env={**os.environ, "PYTHONHASHSEED": str(hash_seed)},
            timeout=120,
        ).stdout.strip()
        for hash_seed in (1, 2)
    ]
    assert outputs[0] == outputs[1]
    assert outputs[0] == determinism_output_here()  # and the same as in this process


def random_robots(count: int, seed: int) -> list:
    """Robots of mixed kinds, shapes, labels, genes and settings (so several batch groups)."""
    rng = np.random.default_rng(seed)
    sims = [
        sim_settings({"duration": 0.5, "settle_time": 0.2}),
        sim_settings({"duration": 0.5, "settle_time": 0.2, "friction": 0.9, "omega": 4.0}),
        sim_settings({"duration": 0.5, "settle_time": 0.1, "drop_height": 0.05, "damping": 0.999}),
    ]
    robots: list = []
    while len(robots) < count:
        sim = sims[rng.integers(len(sims))]
        kind = rng.integers(4)
        if kind == 0:
            shape = ((2, 2, 1), (3, 1, 1), (2, 2, 2))[rng.integers(3)]
            size = shape[0] * shape[1] * shape[2]
            labels = tuple(
                rng.choice(["empty", "soft", "hard", "sine", "neg_sine"], size, p=[0.2] * 5)
            )
            if all(label == "empty" for label in labels):
                continue
            genes = Actuation(*(float(v) for v in rng.uniform(-1, 1, 3)))
            robots.append(VoxelRobot(shape, labels, genes, sim))
        elif kind == 1:  # passive: omega 0, a group of its own
            robots.append(VoxelRobot((2, 2, 1), ("hard", "soft", "soft", "hard"), Actuation(), sim))
        elif kind == 2:
            options = PAPER_OPTIONS[rng.integers(0, 4, 28)]
            robots.append(SpringRobot((1, 1, 1), (True,), options, sim))
        else:
            n = full_lattice((2, 1, 1)).n_springs
            labels = tuple(SPRING_LABELS[i] for i in rng.integers(0, 4, n))
            genes = Actuation(*(float(v) for v in rng.uniform(-1, 1, 3)))
            robots.append(LabelledSpringRobot((2, 1, 1), (True, True), labels, genes, sim))
    return robots


@functools.cache
def batch_case() -> tuple[list, list]:
    """24 mixed robots and their results simulated one at a time."""
    robots = random_robots(24, seed=7)
    return robots, [simulate(robot)[0] for robot in robots]


BATCH_LAYOUTS = [(1, 3), (2, 2), (2, 32), (1, 1)]


@pytest.mark.parametrize(("threads", "lanes"), BATCH_LAYOUTS)
def test_batch_positions_are_bit_identical_to_one_at_a_time(threads: int, lanes: int) -> None:
    robots, alone = batch_case()
    batched = simulate_batch(robots, threads=threads, lanes=lanes)
    assert len(batched) == len(robots)
    mechs = [build_mechanics(robot) for robot in robots]
    assert len({m.lattice.shape for m in mechs}) >= 3  # the batch really mixes shapes
    assert len({(m.lattice.shape, m.sim, m.omega) for m in mechs}) >= 6  # and groups
    for one, many in zip(alone, batched, strict=True):
        assert one.stable and many.stable
        assert (one.masses, one.springs) == (many.masses, many.springs)
        assert one.final_positions.tobytes() == many.final_positions.tobytes()


@pytest.mark.parametrize(("threads", "lanes"), BATCH_LAYOUTS)
def test_batch_fitness_is_bit_identical_to_one_at_a_time(threads: int, lanes: int) -> None:
    """Centres of mass and speed, not only positions: fitness must not depend on batching."""
    robots, alone = batch_case()
    batched = simulate_batch(robots, threads=threads, lanes=lanes)
    for index, (one, many) in enumerate(zip(alone, batched, strict=True)):
        assert one.com_start == many.com_start, f"robot {index}"
        assert one.com_end == many.com_end, f"robot {index}"
        assert one.speed == many.speed, f"robot {index}"


def test_batch_of_robots_with_different_masses_pads_correctly() -> None:
    """Same shape and settings, different occupancy: one group with padding masses and springs."""
    sim = short(duration=0.5, settle_time=0.2)
    grids = [
        ("sine", "hard", "hard", "neg_sine"),
        ("sine", "empty", "hard", "neg_sine"),
        ("empty", "empty", "soft", "sine"),
    ]
    robots = [VoxelRobot((2, 2, 1), labels, Actuation(0.1, 1.0, 0.3), sim) for labels in grids]
    assert len({build_mechanics(robot).n_masses for robot in robots}) == 3
    for one, many in zip([simulate(r)[0] for r in robots], simulate_batch(robots), strict=True):
        assert one.final_positions.tobytes() == many.final_positions.tobytes()
        assert one.com_end == many.com_end


def test_batch_refuses_bad_thread_or_lane_counts() -> None:
    with pytest.raises(ValueError, match="threads"):
        simulate_batch([], threads=0)
    with pytest.raises(ValueError, match="lanes"):
        simulate_batch([], lanes=0)


def test_a_robot_whose_integration_diverged_is_unstable_not_fast() -> None:
    """Past the time step's stability limit (dt = 3 ms against a 10 kN/m ground) robots blow up:
    some to NaN, some to huge but finite positions, which once read as speeds of 1e70 m/s and
    won the run. Every such robot is unstable with a NaN speed; a robot at the paper's dt is
    stable, its springs nowhere near the stretch limit."""
    from softevo.core.config import resolve
    from softevo.core.evolution import Evolution
    from softevo.core.physics.simulate import MAX_STRETCH

    request = {"preset": "quick", "seed": 4, "population": 16, "generations": 1}
    for dt, diverges in ((0.003, True), (0.0005, False)):
        sim = {"profile": "paper", "duration": 1.5, "settle_time": 0.3, "dt": dt}
        config = resolve({**request, "sim": sim})
        evolution = Evolution.start(config)
        robots = [evolution.robot(item) for item in evolution.individuals()]
        results = simulate_batch(robots)
        for result in results:
            assert result.stable == np.isfinite(result.speed)
            assert not result.stable or abs(result.speed) < 5.0, result.speed  # damping caps ~0.5
        unstable = [r for r in results if not r.stable]
        assert bool(unstable) == diverges
        if diverges:  # some diverged robots are finite: the stretch test is what catches them
            assert any(np.isfinite(r.final_positions).all() for r in unstable)
    healthy = simulate(robots[0])[0]
    ends = healthy.final_positions
    mech = build_mechanics(robots[0])
    a, b = mech.lattice.springs.T
    stretch = np.linalg.norm(ends[a] - ends[b], axis=1) / mech.rest_length
    assert stretch.max() < MAX_STRETCH / 2
