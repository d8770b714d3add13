"""Analytic cases of voxel bodies: a block sliding or sticking on a slope (Coulomb), a column
compressed by its own weight and a cantilever bent by it (docs/physics.md, "Checked against
closed forms"). Shared by the tests and bench/analytic_figures.py, like analytic_cases.py.

**The lattice's elastic constants.** Under a uniform strain a voxel's deformation is affine and
its 28 springs (merged springs are sums, so each voxel owns its own) store
(k / 2) sum L_s^2 e_s^2 with e_s = sum_a c_a^2 e_a, c the spring's direction cosines. Summing
the 12 edges, 12 face diagonals and 4 body diagonals of a cube of edge a gives the stiffness
C11 = (28 / 3) k / a and C12 = C44 = (10 / 3) k / a (central forces: Cauchy's relation), so
a bar with free sides (uniaxial stress) has Young's modulus E = C11 - 2 C12^2 / (C11 + C12)
= (144 / 19) k / a = 7.58 k / a and Poisson's ratio 10 / 38; with its sides held it is C11.

**A beam one voxel thick.** In pure bending the face diagonals and body diagonals of the
bending plane join the stretched fibre to the compressed one and stay their length, so only the
top and bottom faces store energy: each is a sheet of x edges, y edges and diagonals whose
energy, minimised over its sideways strain (-e / 3), is (k / 2)(8 / 3) a^2 e^2 per voxel at a
fibre strain e = kappa a / 2. Hence EI = (4 / 3) k a^3 (a continuum bar of modulus E and
I = a^4 / 12 would have 0.63 k a^3: half as stiff), and the shear stiffness from the diagonals
is GA = (10 / 3) k a.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from softevo.core.physics import kernels, simulate
from softevo.core.physics.simulate import ground_damping, spring_dashpots
from softevo.core.robots.robot import Actuation, Mechanics, VoxelRobot, build_mechanics
from softevo.core.robots.terrain import kernel_params
from tests.core.physics.analytic_cases import MASS, G, K, physical

MU = 0.6  # the friction coefficient of the slope cases (the paper's)
C11, C12 = 28.0 / 3.0, 10.0 / 3.0  # the lattice's elastic constants, in k / a
MODULUS = C11 - 2.0 * C12**2 / (C11 + C12)  # Young's modulus with free sides, in k / a
BENDING, SHEAR = 4.0 / 3.0, 10.0 / 3.0  # EI (k a^3) and GA (k a) of a beam one voxel thick


@dataclass(frozen=True)
class Slide:
    """How far a block's centre of mass moved down a slope (m) over time (s)."""

    times: np.ndarray
    along: np.ndarray
    angle_deg: float

    @property
    def closed_form(self) -> float:
        """g (sin t - mu cos t) down the slope above the friction angle, 0 below it."""
        angle = math.radians(self.angle_deg)
        return max(G * (math.sin(angle) - MU * math.cos(angle)), 0.0)

    def acceleration(self, after: float = 0.2) -> float:
        """Twice the t^2 term of a least-squares parabola through the motion from `after` s
        (once the contact has settled)."""
        kept = self.times >= after
        return float(2.0 * np.polyfit(self.times[kept], self.along[kept], 2)[0])

    def moved(self, after: float = 0.2) -> float:
        """The distance moved (m) from `after` s to the end."""
        start = int(np.searchsorted(self.times, after))
        return float(self.along[-1] - self.along[start])


def flat_on_slope(mech: Mechanics, angle: float) -> Mechanics:
    """`mech` turned to lie with its base on a slope of `angle` (rad) through the origin, sunk
    to the depth where the ground holds its weight: 2 m g cos(angle) / k_g for each of the four
    corners of a cube's base (an upright cube on a slope would tip onto it and tumble)."""
    sim = mech.sim
    tangent = np.array([math.cos(angle), 0.0, math.sin(angle)])
    normal = np.array([-math.sin(angle), 0.0, math.cos(angle)])
    depth = 2.0 * sim.mass * G * math.cos(angle) / sim.ground_stiffness
    rest = mech.lattice.rest_positions * sim.edge_length
    positions = (
        rest[:, :1] * tangent + rest[:, 1:2] * [0.0, 1.0, 0.0] + (rest[:, 2:] - depth) * normal
    )
    return dataclasses.replace(mech, positions=positions)


def slide(angle_deg: float, divide: float = 1.0, duration: float = 2.0) -> Slide:
    """One hard voxel laid on a slope of `angle_deg`, no drag, friction `MU`."""
    sim = physical(
        divide,
        duration=duration,
        drag=0.0,
        friction=MU,
        terrain={"kind": "slope", "angle_deg": angle_deg},
    )
    angle = math.radians(angle_deg)
    mech = flat_on_slope(build_mechanics(VoxelRobot((1, 1, 1), ("hard",), Actuation(), sim)), angle)
    _, trajectory = simulate(mech, record_every=10)
    assert trajectory is not None
    com = trajectory.frames.mean(axis=1)
    along = -(com[:, 0] * math.cos(angle) + com[:, 2] * math.sin(angle))
    return Slide(trajectory.times, along - along[0], angle_deg)


@dataclass(frozen=True)
class Column:
    """A 1x1xN column of hard voxels standing on the ground: how much each of its N + 1 planes
    of four masses has come down relative to the bottom plane (m), at rest."""

    voxels: int
    friction: float
    shortening: np.ndarray  # [N + 1]: 0 for the bottom plane

    def closed_form(self, modulus: float = MODULUS) -> np.ndarray:
        """A stack of N springs of stiffness E a (A = a^2): layer i carries the N - i planes
        above it, 4 m g each, so plane j has come down sum_{i < j} 4 m g (N - i) / (E a)."""
        load = 4 * MASS * G * (self.voxels - np.arange(self.voxels))
        return np.concatenate([[0.0], np.cumsum(load / (modulus * K))])


def column(voxels: int, friction: float = 0.0, duration: float = 3.0) -> Column:
    """The column dropped from 0 in the physical profile (its dampings settle it) and read at
    the end. With no friction its base spreads freely (uniaxial stress); with friction the
    ground holds the base's corners and the bottom is stiffer."""
    sim = physical(duration=duration, friction=friction)
    robot = VoxelRobot((1, 1, voxels), ("hard",) * voxels, Actuation(), sim)
    mech = build_mechanics(robot)
    result, _ = simulate(mech, energy=False)
    height = mech.positions[:, 2].round(9)
    planes = np.unique(height)
    start = np.array([height[height == z].mean() for z in planes])
    end = np.array([result.final_positions[height == z, 2].mean() for z in planes])
    moved = start - end
    return Column(voxels, friction, moved - moved[0])


def run_pinned(mech: Mechanics, pinned: np.ndarray) -> np.ndarray:
    """Positions [M, 3] after `sim.n_steps` steps with the masses `pinned` held still (step
    factor 0), through the kernel that `simulate` calls."""
    sim, n, springs = mech.sim, mech.n_masses, mech.lattice.springs
    x, y, z = (np.ascontiguousarray(column) for column in mech.positions.T)
    state = (x, y, z, np.zeros(n), np.zeros(n), np.zeros(n))
    ends = (np.ascontiguousarray(springs[:, 0]), np.ascontiguousarray(springs[:, 1]))
    spring = (mech.stiffness, mech.rest_length, mech.amp_sin, mech.amp_cos, spring_dashpots(mech))
    steps = (mech.omega, sim.step, sim.n_steps, sim.mass * sim.gravity, sim.ground_stiffness)
    ground = (ground_damping(sim), sim.friction, sim.velocity_factor, *kernel_params(sim.terrain))
    unused = (0, np.empty(n), np.empty(n), np.empty(n), 0, np.empty((0, 3, n)), np.zeros(0))
    factor = np.where(pinned, 0.0, sim.step / sim.mass)
    kernels.simulate_one(*state, factor, *ends, *spring, *steps, *ground, *unused)
    return np.stack([x, y, z], axis=1)


def beam_deflection(
    voxels: int, at: np.ndarray, gravity: float = G, shear: bool = False
) -> np.ndarray:
    """Euler-Bernoulli deflection (m) at `at` of a cantilever of `voxels` one-voxel cells,
    clamped at x = 0 and loaded at its node planes x_j = j a (j = 1 .. N) by 4 m g each:
    sum_j P x^2 (3 x_j - x) / 6 EI (x <= x_j; x_j^2 (3 x - x_j) past it); with `shear` also
    Timoshenko's P min(x, x_j) / GA."""
    load = 4 * MASS * gravity
    nodes = np.arange(1, voxels + 1, dtype=np.float64)[None, :]
    x = np.asarray(at, dtype=np.float64)[:, None]
    near = np.minimum(x, nodes)
    far = np.maximum(x, nodes)
    bend = load * near**2 * (3 * far - near) / (6 * BENDING * K)
    total = bend + (load * near / (SHEAR * K) if shear else 0.0)
    return total.sum(axis=1)


@dataclass(frozen=True)
class Cantilever:
    """A 1x1 beam of N hard voxels clamped at x = 0: each node plane's deflection (m), at rest,
    under the gravity that makes Euler-Bernoulli's tip deflection `sag` of the length."""

    voxels: int
    gravity: float
    positions: np.ndarray  # [N + 1] x of the node planes (m)
    deflection: np.ndarray  # [N + 1]

    @property
    def error(self) -> float:
        """The tip deflection's relative difference from Euler-Bernoulli's."""
        tip = beam_deflection(self.voxels, self.positions[-1:], self.gravity)[0]
        return float(self.deflection[-1] / tip - 1.0)


def cantilever(voxels: int, sag: float = 0.005) -> Cantilever:
    """The beam far above the ground, its x = 0 plane pinned, the rest settled by a drag of
    twice its first bending mode's w1 = 3.516 sqrt(EI / (rho A L^4)) (near critical, so it
    settles fastest; the rest state does not depend on the drag) over 25 / w1 s."""
    length = float(voxels)
    unit_sag = beam_deflection(voxels, np.array([length]), 1.0)[0]
    gravity = sag * length / unit_sag  # linear: the deflection is proportional to g
    omega_1 = 3.516 * math.sqrt(BENDING * K / (4 * MASS * length**4))
    sim = physical(
        drop_height=10.0, gravity=-gravity, drag=2 * omega_1, duration=max(2.0, 25.0 / omega_1)
    )
    mech = build_mechanics(VoxelRobot((voxels, 1, 1), ("hard",) * voxels, Actuation(), sim))
    end = run_pinned(mech, mech.positions[:, 0] == mech.positions[:, 0].min())
    planes = np.unique(mech.positions[:, 0].round(9))
    sink = mech.positions[:, 2] - end[:, 2]
    deflection = np.array([sink[mech.positions[:, 0].round(9) == x].mean() for x in planes])
    return Cantilever(voxels, gravity, planes, deflection)
