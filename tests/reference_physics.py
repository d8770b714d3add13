"""A slow, obviously-right NumPy reference of the physics in docs/physics.md ("One step").

Written from the equations, not from the numba kernel, and kept as plain as possible: one
vectorised NumPy pass per step, 3-vectors as rows of [M, 3] arrays, forces scattered with
`np.add.at`, friction written with an explicit "stick or slide" choice. The kernel is tested
against it in tests/core/physics/test_physics.py.

Per step n (t = n * dt, state x_n, v_n; all masses weigh m):

1. rest length of each spring: L0 = rest + amp_sin sin(w t) + amp_cos cos(w t);
2. spring (i, j): delta = x_j - x_i, d = |delta|, tension T = k (d - L0) + c (d - d_prev) / dt,
   F_i += T delta / d, F_j -= the same (d is floored at 1e-12 so a collapsed spring gives no
   0 / 0). The dashpot c = 2 zeta sqrt(k m / 2) (zeta = `material_damping`, m / 2 the reduced
   mass of two equal masses) acts on the change of the length since the last step; d_prev is
   the length at step n - 1, the initial length at step 0;
3. weight m g along z, ground normal force Fn = k_g max(-z, 0) along +z; in contact (Fn > 0)
   a dashpot c_g = 2 zeta_c sqrt(k_g m) (zeta_c = `contact_damping`) adds c_g (-v_z), v the
   velocity at step n, and the sum never pulls: Fn = max(k_g depth + c_g (-v_z), 0);
4. u = v + dt (F + Fn e_z) / m;
5. Coulomb friction as a velocity change of at most mu Fn dt / m against the horizontal
   velocity: a mass slower than that sticks (its horizontal velocity becomes 0);
6. v_{n+1} = f u, f = damping exp(-drag dt) (the legacy per-step factor times a decay rate in
   s^-1);  7. x_{n+1} = x_n + dt v_{n+1}.

dt is `sim.step`: the `dt` set, or `dt_fraction` of the critical step where it is null.

On a terrain other than flat, 3 and 5 use the surface's normal n and penetration depth
(`terrain_contact`) instead of e_z and -z (the dashpot's approach speed is -v . n), and
friction acts on u's part in the tangent plane.
Actuator work: the sum over springs and steps from the settle step on of dt |T dL0/dt|.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from softevo.core.robots.robot import Mechanics

#: Smallest spring length divided by (a collapsed spring exerts no force instead of 0 / 0).
SPRING_LENGTH_FLOOR = 1e-12


@dataclass(frozen=True)
class ReferenceRun:
    """Positions [M, 3] at the settle step and at the end, the recorded frames [F, M, 3] and the
    actuators' work."""

    settle_positions: np.ndarray
    final_positions: np.ndarray
    frames: np.ndarray
    frame_steps: np.ndarray
    energy: float  # actuators' work from the settle step on (J)


def spring_rest_lengths(mech: Mechanics, t: float) -> np.ndarray:
    """L0(t) of every spring (m)."""
    w = mech.omega
    return mech.rest_length + mech.amp_sin * np.sin(w * t) + mech.amp_cos * np.cos(w * t)


def spring_lengths(mech: Mechanics, positions: np.ndarray) -> np.ndarray:
    """|x_j - x_i| of every spring (m)."""
    i, j = mech.lattice.springs[:, 0], mech.lattice.springs[:, 1]
    return np.linalg.norm(positions[j] - positions[i], axis=1)


def spring_forces(
    mech: Mechanics, positions: np.ndarray, t: float, last: np.ndarray | None = None
) -> np.ndarray:
    """Net spring force on every mass, [M, 3] (N); with `last`, the springs' lengths at the
    last step, the dashpots' force c (d - last) / dt too."""
    i, j = mech.lattice.springs[:, 0], mech.lattice.springs[:, 1]
    delta = positions[j] - positions[i]  # from i towards j
    d = np.linalg.norm(delta, axis=1)
    tension = mech.stiffness * (d - spring_rest_lengths(mech, t))  # > 0: stretched, pulls in
    if last is not None:
        sim = mech.sim
        dashpot = 2.0 * sim.material_damping * np.sqrt(mech.stiffness * sim.mass / 2.0)
        tension = tension + dashpot * (d - last) / sim.step
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


def terrain_contact(terrain: object, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Penetration depth [M] into the terrain and the outward unit normal [M, 3] of the surface
    there (docs/physics.md "Terrain"): a height field's depth is measured along its normal,
    (h - z) / |(-h_x, -h_y, 1)|; inside a step or a bar the nearest face wins (the tread or top
    by +z, a riser or bar face by -x or +x; the top on a tie, the front on a front/back tie)."""
    px, py, pz = x[:, 0], x[:, 1], x[:, 2]
    normal = np.zeros_like(x)
    normal[:, 2] = 1.0
    kind = terrain.kind
    if kind == "flat":
        return np.maximum(-pz, 0.0), normal
    if kind in ("slope", "rough"):
        if kind == "slope":
            h = px * np.tan(np.radians(terrain.angle_deg))
            hx, hy = np.full_like(px, np.tan(np.radians(terrain.angle_deg))), np.zeros_like(px)
        else:
            waves = terrain.waves()
            angle = waves[:, 0] * px[:, None] + waves[:, 1] * py[:, None] + waves[:, 2]
            h = (waves[:, 3] * np.cos(angle)).sum(axis=1)
            hx = -(waves[:, 3] * np.sin(angle) * waves[:, 0]).sum(axis=1)
            hy = -(waves[:, 3] * np.sin(angle) * waves[:, 1]).sum(axis=1)
        norm = np.sqrt(1.0 + hx**2 + hy**2)
        inside = pz < h
        normal = np.stack([-hx, -hy, np.ones_like(px)], axis=1) / norm[:, None]
        return np.where(inside, (h - pz) / norm, 0.0), normal
    depth = np.maximum(-pz, 0.0)
    if kind == "steps":
        index = np.maximum(np.floor(px / terrain.depth), 0.0)
        top = index * terrain.height
        face = px - index * terrain.depth
        inside = pz < top
        use_face = inside & (index >= 1) & (face < top - pz)
        depth = np.where(inside, np.where(use_face, face, top - pz), 0.0)
        normal[use_face] = (-1.0, 0.0, 0.0)
        return depth, normal
    # hurdles
    index = np.floor(px / terrain.spacing)
    along = px - index * terrain.spacing
    on_bar = (index >= 1) & (along <= terrain.width) & (pz < terrain.height)
    top, back = terrain.height - pz, terrain.width - along
    front_wins = on_bar & (along < top) & (along <= back)
    back_wins = on_bar & ~front_wins & (back < top)
    top_wins = on_bar & ~front_wins & ~back_wins
    depth = np.where(front_wins, along, np.where(back_wins, back, np.where(top_wins, top, depth)))
    normal[front_wins] = (-1.0, 0.0, 0.0)
    normal[back_wins] = (1.0, 0.0, 0.0)
    return depth, normal


def actuator_power(mech: Mechanics, positions: np.ndarray, t: float) -> np.ndarray:
    """|T dL0/dt| of every spring (W): its tension times the rate its actuator changes L0."""
    i, j = mech.lattice.springs[:, 0], mech.lattice.springs[:, 1]
    d = np.linalg.norm(positions[j] - positions[i], axis=1)
    tension = mech.stiffness * (d - spring_rest_lengths(mech, t))
    w = mech.omega
    rate = w * (mech.amp_sin * np.cos(w * t) - mech.amp_cos * np.sin(w * t))
    return np.abs(tension * rate)


def velocity_factor(mech: Mechanics) -> float:
    """What every velocity is multiplied by each step: damping exp(-drag dt)."""
    sim = mech.sim
    return float(sim.damping * np.exp(-sim.drag * sim.step))


def normal_force(mech: Mechanics, depth: np.ndarray, approach: np.ndarray) -> np.ndarray:
    """The ground's push [M] (N): k_g depth, and in contact the dashpot on the speed `approach`
    into the ground, never pulling."""
    sim = mech.sim
    spring = sim.ground_stiffness * depth
    dashpot = 2.0 * sim.contact_damping * np.sqrt(sim.ground_stiffness * sim.mass)
    in_contact = spring > 0.0
    return np.where(in_contact, np.maximum(spring + dashpot * approach, 0.0), 0.0)


def step(
    mech: Mechanics, x: np.ndarray, v: np.ndarray, n: int, last: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """One semi-implicit Euler step from (x_n, v_n) to (x_{n+1}, v_{n+1}); `last`: the springs'
    lengths at step n - 1 (the dashpots')."""
    sim = mech.sim
    m, dt = sim.mass, sim.step
    t = n * dt
    force = spring_forces(mech, x, t, last if sim.material_damping > 0 else None)
    force[:, 2] += m * sim.gravity
    if sim.terrain.kind != "flat":
        return _terrain_step(mech, x, v, force)
    normal = normal_force(mech, np.maximum(-x[:, 2], 0.0), -v[:, 2])
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

    v_next = velocity_factor(mech) * u
    x_next = x + dt * v_next
    return x_next, v_next


def _terrain_step(
    mech: Mechanics, x: np.ndarray, v: np.ndarray, force: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Steps 3-7 on any terrain: the normal force along the surface normal n, and friction
    against the part of u in the tangent plane, u - (u . n) n."""
    sim = mech.sim
    m, dt = sim.mass, sim.step
    depth, n = terrain_contact(sim.terrain, x)
    normal = normal_force(mech, depth, -(v * n).sum(axis=1))
    u = v + dt * (force + normal[:, None] * n) / m
    along = (u * n).sum(axis=1)
    tangent = u - along[:, None] * n
    speed = np.linalg.norm(tangent, axis=1)
    max_change = sim.friction * normal * dt / m
    scale = np.where(speed <= max_change, 0.0, 1.0 - max_change / np.where(speed > 0, speed, 1.0))
    u = tangent * scale[:, None] + along[:, None] * n
    v_next = velocity_factor(mech) * u
    return x + dt * v_next, v_next


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
    work = np.zeros(mech.n_springs)
    last = spring_lengths(mech, x)  # the dashpots' d_prev at step 0: the initial lengths
    for n in range(n_steps):
        if record_every > 0 and n % record_every == 0:
            frames.append(x.copy())
            frame_steps.append(n)
        if n >= settle_step:
            work += sim.step * actuator_power(mech, x, n * sim.step)
        lengths = spring_lengths(mech, x)
        x, v = step(mech, x, v, n, last)
        last = lengths
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
        energy=float(work.sum()),
    )
