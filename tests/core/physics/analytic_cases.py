"""Analytic cases of the validation suite, free of contact: a mass on a spring, free fall and
energy without damping (docs/physics.md, "Checked against closed forms"). Each builds a small
system in the physical profile, simulates it with the kernels and returns what a closed form
predicts beside what was measured. Shared by the tests (test_analytic_*.py) and by
bench/analytic_figures.py, so the figures show what the tests check."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from softevo.core.physics import simulate
from softevo.core.robots.lattice import Lattice
from softevo.core.robots.robot import Actuation, Mechanics, VoxelRobot, build_mechanics
from softevo.core.robots.settings import SimSettings, sim_settings

#: Gravity (m/s^2), the spring of the oscillator (N/m: the hard material) and every point's mass.
G, K, MASS = 9.81, 2000.0, 0.1


def physical(divide: float = 1.0, **overrides: Any) -> SimSettings:
    """The physical profile with `overrides`, the clock from 0, at its derived step / `divide`."""
    sim = sim_settings({"profile": "physical", "settle_time": 0.0, **overrides})
    return sim_settings({"dt": sim.step / divide}, base=sim) if divide != 1.0 else sim


def spring_pair(sim: SimSettings, stiffness: float, stretch: float) -> Mechanics:
    """Two masses joined by one spring of rest length `edge_length`, stretched by `stretch` of
    it, along x at `drop_height` (a lattice of its own: two points, one spring)."""
    lattice = Lattice(
        shape=(1, 1, 1),
        kept=np.ones(1, dtype=bool),
        points=np.array([0, 1]),
        rest_positions=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]),
        springs=np.array([[0, 1]]),
        spring_lengths=np.ones(1),
        spring_voxels=np.zeros((0, 2), dtype=np.int64),
    )
    length = sim.edge_length
    positions = np.array(
        [[0.0, 0.0, sim.drop_height], [length * (1 + stretch), 0.0, sim.drop_height]]
    )
    zero = np.zeros(1)
    return Mechanics(
        lattice, positions, np.array([stiffness]), np.array([length]), zero, zero, 0.0, sim
    )


@dataclass(frozen=True)
class Oscillation:
    """The extension d - L (m) of a free spring pair over time (s), and its parameters."""

    times: np.ndarray
    extension: np.ndarray
    step: float
    zeta: float
    drag: float

    @property
    def omega_n(self) -> float:
        """The relative mode of two equal masses: sqrt(k / (m / 2))."""
        return math.sqrt(2.0 * K / MASS)

    @property
    def decay(self) -> float:
        """The closed form's decay rate (s^-1): zeta w_n from the dashpot, drag / 2 from the
        drag (it slows each mass, so the relative motion at half its rate on the amplitude)."""
        return self.zeta * self.omega_n + self.drag / 2.0

    @property
    def omega_d(self) -> float:
        """The damped frequency sqrt(w_n^2 - s^2) (rad/s); 0 at or past critical damping."""
        return math.sqrt(max(self.omega_n**2 - self.decay**2, 0.0))

    def closed_form(self, times: np.ndarray) -> np.ndarray:
        """e0 exp(-s t) (cos w_d t + s / w_d sin w_d t): released from rest at e0; at critical
        damping (s = w_n) e0 (1 + w_n t) exp(-w_n t)."""
        s, w, e0 = self.decay, self.omega_d, self.extension[0]
        if w == 0.0:
            return e0 * (1.0 + s * times) * np.exp(-s * times)
        return e0 * np.exp(-s * times) * (np.cos(w * times) + s / w * np.sin(w * times))

    def discrete_decay(self) -> float:
        """Semi-implicit Euler's own decay rate: the dashpot acts on the last step's velocity,
        so |z|^2 = (1 - 2 zeta w_n dt) f per step (f the drag factor): first order in dt."""
        dt = self.step
        return -math.log(1.0 - 2.0 * self.zeta * self.omega_n * dt) / (2 * dt) + self.drag / 2.0


def oscillation(
    zeta: float, drag: float = 0.0, divide: float = 1.0, duration: float = 0.5
) -> Oscillation:
    """A hard spring between two free masses (no gravity, far above the ground), released 5 %
    stretched, with dashpot ratio `zeta` and `drag` (s^-1), at the profile's step / `divide`."""
    sim = physical(
        divide, gravity=0.0, drop_height=10.0, duration=duration, material_damping=zeta, drag=drag
    )
    _, trajectory = simulate(spring_pair(sim, K, 0.05), record_every=1)
    assert trajectory is not None
    frames = trajectory.frames
    extension = frames[:, 1, 0] - frames[:, 0, 0] - sim.edge_length
    return Oscillation(trajectory.times, extension, sim.step, zeta, drag)


def period(osc: Oscillation) -> float:
    """Mean time between upward zero crossings, each interpolated linearly between steps."""
    e, t = osc.extension, osc.times
    up = np.flatnonzero((e[:-1] < 0) & (e[1:] >= 0))
    crossings = t[up] - e[up] * (t[up + 1] - t[up]) / (e[up + 1] - e[up])
    return float(np.diff(crossings).mean())


def peaks(osc: Oscillation) -> tuple[np.ndarray, np.ndarray]:
    """Times and heights of the extension's maxima, refined by a parabola through three steps."""
    e, t = osc.extension, osc.times
    top = np.flatnonzero((e[1:-1] > e[:-2]) & (e[1:-1] >= e[2:])) + 1
    before, at, after = e[top - 1], e[top], e[top + 1]
    shift = 0.5 * (before - after) / (before - 2 * at + after)
    return t[top] + shift * (t[1] - t[0]), at - 0.25 * (before - after) * shift


def decay_rate(osc: Oscillation) -> float:
    """The amplitude's decay rate (s^-1): a least-squares line through log(peak) against time,
    over the peaks above 1e-6 of the first (below, rounding would count)."""
    times, heights = peaks(osc)
    kept = heights > 1e-6 * heights[0]
    return float(-np.polyfit(times[kept], np.log(heights[kept]), 1)[0])


@dataclass(frozen=True)
class Fall:
    """A cube's centre of mass falling: its height (m) and downward speed (m/s) over time."""

    times: np.ndarray
    height: np.ndarray
    speed: np.ndarray  # (z_{n-1} - z_n) / dt: exactly the velocity semi-implicit Euler keeps
    step: float
    drag: float

    def closed_form(self) -> tuple[np.ndarray, np.ndarray]:
        """z0 - g t^2 / 2 and g t; with drag c: z0 - (g / c) t + (g / c^2)(1 - e^-ct) and
        (g / c)(1 - e^-ct), tending to the terminal speed g / c."""
        t, c, z0 = self.times, self.drag, self.height[0]
        if c == 0.0:
            return z0 - G * t**2 / 2, G * t
        fade = 1.0 - np.exp(-c * t)
        return z0 - G / c * t + G / c**2 * fade, G / c * fade


def fall(drag: float = 0.0, divide: float = 1.0, duration: float = 2.0) -> Fall:
    """A hard cube dropped from 100 m (never near the ground), `drag` (s^-1), at step / `divide`."""
    sim = physical(divide, drop_height=100.0, duration=duration, drag=drag)
    _, trajectory = simulate(VoxelRobot((1, 1, 1), ("hard",), Actuation(), sim), record_every=1)
    assert trajectory is not None
    height = trajectory.frames[:, :, 2].mean(axis=1)
    speed = np.concatenate([[0.0], -np.diff(height) / sim.step])
    return Fall(trajectory.times, height, speed, sim.step, drag)


def undamped_body(divide: float = 1.0, duration: float = 5.0, drop: float = 200.0) -> Mechanics:
    """A 3x2x1 hard and soft body stretched and jostled out of rest, falling freely from `drop`
    m with every damping off (drag, material and contact 0: the profile's undamped step)."""
    sim = physical(
        divide,
        drag=0.0,
        material_damping=0.0,
        contact_damping=0.0,
        drop_height=drop,
        duration=duration,
    )
    labels = ("hard", "soft", "hard", "soft", "hard", "hard")
    mech = build_mechanics(VoxelRobot((3, 2, 1), labels, Actuation(), sim))
    centre = mech.positions.mean(axis=0)
    noise = np.random.default_rng(0).normal(0.0, 0.01, mech.positions.shape)
    positions = centre + (mech.positions - centre) * [1.05, 0.97, 1.0] + noise
    return dataclasses.replace(mech, positions=positions)


def elastic_energy(mech: Mechanics, frames: np.ndarray) -> np.ndarray:
    """sum k (d - L)^2 / 2 over the springs, for every frame [F, M, 3] (J)."""
    i, j = mech.lattice.springs[:, 0], mech.lattice.springs[:, 1]
    d = np.linalg.norm(frames[:, j] - frames[:, i], axis=2)
    return 0.5 * (mech.stiffness * (d - mech.rest_length) ** 2).sum(axis=1)


def total_energy(mech: Mechanics) -> tuple[np.ndarray, np.ndarray, float]:
    """Times, kinetic + elastic + gravitational energy (J) at steps 1 .. n-1, and the elastic
    energy stored at the start. Velocities are central differences (x_{n+1} - x_{n-1}) / 2 dt,
    for which symplectic Euler keeps free fall's energy exactly (kinetic g^2 dt^2 (n + 1/2)^2 / 2
    against potential -g^2 dt^2 n (n + 1) / 2 per unit mass: a constant g^2 dt^2 / 8)."""
    _, trajectory = simulate(mech, record_every=1)
    assert trajectory is not None
    x, dt, sim = trajectory.frames, mech.sim.step, mech.sim
    v = (x[2:] - x[:-2]) / (2 * dt)
    kinetic = 0.5 * sim.mass * np.sum(v * v, axis=(1, 2))
    weight = -sim.mass * sim.gravity * x[1:-1, :, 2].sum(axis=1)
    energy = kinetic + elastic_energy(mech, x[1:-1]) + weight
    return trajectory.times[1:-1], energy, float(elastic_energy(mech, mech.positions[None])[0])


def energy_error(divide: float = 1.0, duration: float = 5.0) -> tuple[float, float]:
    """The largest deviation of the total energy from its first value, and the drift (mean of
    the last fifth minus that of the first), both as fractions of the stored elastic energy."""
    _, energy, stored = total_energy(undamped_body(divide, duration))
    fifth = len(energy) // 5
    deviation = float(np.abs(energy - energy[0]).max()) / stored
    return deviation, float(energy[-fifth:].mean() - energy[:fifth].mean()) / stored
