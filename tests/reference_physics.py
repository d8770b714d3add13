"""A slow, obviously-right NumPy reference of the physics in docs/physics.md ("One step").

Written from the equations, not from the numba kernel, and kept as plain as possible: one
vectorised NumPy pass per step, 3-vectors as rows of [M, 3] arrays, forces scattered with
`np.add.at`, friction written with an explicit "stick or slide" choice. The kernel is tested
against it in tests/core/test_physics.py.

Per step n (t = n * dt, state x_n, v_n; all masses weigh m):

1. rest length of each spring: L0 = rest + amp_sin sin(w t) + amp_cos cos(w t);
2. spring (i, j): delta = x_j - x_i, d = |delta|, F_i += k (d - L0) delta / d, F_j -= the same
   (d is floored at 1e-12 so a collapsed spring gives no 0 / 0);
3. weight m g along z, ground normal force Fn = k_g max(-z, 0) along +z;
4. u = v + dt (F + Fn e_z) / m;
5. Coulomb friction as a velocity change of at most mu Fn dt / m against the horizontal
   velocity: a mass slower than that sticks (its horizontal velocity becomes 0);
6. v_{n+1} = damping * u;  7. x_{n+1} = x_n + dt v_{n+1}.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from softevo.core.robot import Mechanics

#: Smallest spring length divided by (a collapsed spring exerts no force instead of 0 / 0).
SPRING_LENGTH_FLOOR = 1e-12


@dataclass(frozen=True)
class ReferenceRun:
    """Positions [M, 3] at the settle step and at the end, and the recorded frames [F, M, 3]."""

    settle_positions: np.ndarray
    final_positions: np.ndarray
    frames: np.ndarray
    frame_steps: np.ndarray


def spring_rest_lengths(mech: Mechanics, t: float) -> np.ndarray:
    """L0(t) of every spring (m)."""
    w = mech.omega
    return mech.rest_length + mech.amp_sin * np.sin(w * t) + mech.amp_cos * np.cos(w * t)


def spring_forces(mech: Mechanics, positions: np.ndarray, t: float) -> np.ndarray:
    """Net spring force on every mass, [M, 3] (N)."""
    i, j = mech.lattice.springs[:, 0], mech.lattice.springs[:, 1]
    delta = positions[j] - positions[i]  # from i towards j
    d = np.linalg.norm(delta, axis=1)
    tension = mech.stiffness * (d - spring_rest_lengths(mech, t))  # > 0: stretched, pulls in
    along = tension / np.maximum(d, SPRING_LENGTH_FLOOR)
    force_on_i = along[:, None] * delta
    forces = np.zeros_like(positions)
    np.add.at(forces, i, force_on_i)
    np.add.at(forces, j, -force_on_i)
    return forces


def spring_energy(mech: Mechanics, positions: np.ndarray, t: float = 0.0) -> float:
    """Elastic energy sum k (d - L0)^2 / 2 of all springs (J)."""
    i, j = mech.lattice.springs[:, 0], mech.lattice.springs[:, 1]
    d = np.linalg.norm(positions[j] - positions[i], axis=1)
    return float(0.5 * np.sum(mech.stiffness * (d - spring_rest_lengths(mech, t)) ** 2))


def step(mech: Mechanics, x: np.ndarray, v: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """One semi-implicit Euler step from (x_n, v_n) to (x_{n+1}, v_{n+1})."""
    sim = mech.sim
    m, dt = sim.mass, sim.dt
    t = n * dt
    force = spring_forces(mech, x, t)
    force[:, 2] += m * sim.gravity
    normal = sim.ground_stiffness * np.maximum(-x[:, 2], 0.0)
    force[:, 2] += normal
    u = v + dt * force / m

    # Coulomb friction: remove up to mu * Fn * dt / m of horizontal speed, never reversing it.
    horizontal_speed = np.linalg.norm(u[:, :2], axis=1)
    max_change = sim.friction * normal * dt / m
    sticks = horizontal_speed <= max_change
    sliding_scale = np.ones_like(horizontal_speed)
    slides = ~sticks & (horizontal_speed > 0)
    sliding_scale[slides] = 1.0 - max_change[slides] / horizontal_speed[slides]
    sliding_scale[sticks] = 0.0
    u[:, 0] *= sliding_scale
    u[:, 1] *= sliding_scale

    v_next = sim.damping * u
    x_next = x + dt * v_next
    return x_next, v_next


def run(mech: Mechanics, record_every: int = 0) -> ReferenceRun:
    """Simulate `mech` from rest at its initial positions for `sim.n_steps` steps.

    The settle positions are those after `sim.settle_steps` steps; with `record_every` > 0 the
    positions after every multiple of that many steps, and after the last, are recorded too.
    """
    sim = mech.sim
    n_steps, settle_step = sim.n_steps, sim.settle_steps
    x = np.array(mech.positions, dtype=np.float64, copy=True)
    v = np.zeros_like(x)
    settle = x.copy() if settle_step == 0 else None
    frames, frame_steps = [], []
    for n in range(n_steps):
        if record_every > 0 and n % record_every == 0:
            frames.append(x.copy())
            frame_steps.append(n)
        x, v = step(mech, x, v, n)
        if n + 1 == settle_step:
            settle = x.copy()
    if record_every > 0:
        frames.append(x.copy())
        frame_steps.append(n_steps)
    assert settle is not None, "settle step after the last step"
    return ReferenceRun(
        settle_positions=settle,
        final_positions=x,
        frames=np.array(frames).reshape(-1, *x.shape),
        frame_steps=np.array(frame_steps, dtype=np.int64),
    )
