"""`simulate_one`: one robot, springs as a list of mass pairs (the arithmetic is in
`kernels`' docstring and docs/physics.md)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softevo.core.physics.contact import contact_scratch
from softevo.core.physics.integrate import advance
from softevo.core.physics.jit import JIT
from softevo.core.physics.springs import (
    actuator_power,
    damped_spring_force,
    length,
    spring_force,
)


@njit(**JIT)
def simulate_one(
    x,
    y,
    z,
    vx,
    vy,
    vz,  # [M] positions (m), velocities (m/s); updated in place
    step_factor,  # [M] dt / mass, or 0 for a mass that must not move
    spring_a,
    spring_b,  # [S] int64 mass indices (the lattice's order: sorted, a < b)
    stiffness,
    rest,
    amp_sin,
    amp_cos,  # [S] float64
    damp,  # [S] each spring's dashpot over dt (N/m), or [0]: no material damping
    omega,
    dt,
    n_steps,
    weight,
    ground_k,
    ground_c,
    friction,
    damping,
    terrain_kind,
    terrain,  # softevo.core.robots.terrain.kernel_params
    settle_step,
    settle_x,
    settle_y,
    settle_z,  # positions copied when step == settle_step
    record_every,
    frames,  # frames [F, 3, M]: positions every record_every steps, and the last
    energy,  # [S] actuator work of each spring from settle_step on (J), or [0]: not measured
):
    n_masses = x.shape[0]
    n_springs = spring_a.shape[0]
    fx = np.empty(n_masses)
    fy = np.empty(n_masses)
    fz = np.empty(n_masses)
    sfx = np.empty(n_springs)  # spring vectors x_j - x_i, then spring forces f (x_j - x_i)
    sfy = np.empty(n_springs)
    sfz = np.empty(n_springs)
    # The springs of each mass m, in spring order: incident[first[m]:first[m + 1]] holds s where
    # m is spring_a[s] (force +=) and ~s = -1 - s where m is spring_b[s] (force -=).
    first = np.zeros(n_masses + 1, dtype=np.int64)
    for s in range(n_springs):
        first[spring_a[s] + 1] += 1
        first[spring_b[s] + 1] += 1
    for m in range(n_masses):
        first[m + 1] += first[m]
    incident = np.empty(2 * n_springs, dtype=np.int64)
    fill = first[:-1].copy()
    contact = contact_scratch(n_masses)  # terrain contact scratch (`contact_pass`)
    near = np.empty(n_masses, dtype=np.int64)
    for s in range(n_springs):
        incident[fill[spring_a[s]]] = s
        fill[spring_a[s]] += 1
        incident[fill[spring_b[s]]] = ~s
        fill[spring_b[s]] += 1
    damped = damp.shape[0] > 0
    last = np.empty(n_springs if damped else 0)  # each spring's length at the last step
    for s in range(last.shape[0]):
        i = spring_a[s]
        j = spring_b[s]
        last[s] = length(x[j] - x[i], y[j] - y[i], z[j] - z[i])
    frame = 0
    for step in range(n_steps + 1):
        if step == settle_step:
            settle_x[:] = x
            settle_y[:] = y
            settle_z[:] = z
        if record_every > 0 and (step % record_every == 0 or step == n_steps):
            frames[frame, 0, :] = x
            frames[frame, 1, :] = y
            frames[frame, 2, :] = z
            frame += 1
        if step == n_steps:
            break
        t = step * dt
        sin_t = math.sin(omega * t)
        cos_t = math.cos(omega * t)
        # Spring vectors: indexed loads, scalar. Then spring forces: contiguous, so vectorised.
        for s in range(n_springs):
            i = spring_a[s]
            j = spring_b[s]
            sfx[s] = x[j] - x[i]
            sfy[s] = y[j] - y[i]
            sfz[s] = z[j] - z[i]
        if energy.shape[0] > 0 and step >= settle_step:
            for s in range(n_springs):
                energy[s] += dt * actuator_power(
                    sfx[s],
                    sfy[s],
                    sfz[s],
                    stiffness[s],
                    rest[s],
                    amp_sin[s],
                    amp_cos[s],
                    sin_t,
                    cos_t,
                    omega,
                )
        if damped:
            for s in range(n_springs):
                sfx[s], sfy[s], sfz[s], last[s] = damped_spring_force(
                    sfx[s],
                    sfy[s],
                    sfz[s],
                    stiffness[s],
                    rest[s],
                    amp_sin[s],
                    amp_cos[s],
                    sin_t,
                    cos_t,
                    damp[s],
                    last[s],
                )
        else:
            for s in range(n_springs):
                sfx[s], sfy[s], sfz[s] = spring_force(
                    sfx[s],
                    sfy[s],
                    sfz[s],
                    stiffness[s],
                    rest[s],
                    amp_sin[s],
                    amp_cos[s],
                    sin_t,
                    cos_t,
                )
        # Force on each mass, summed in registers in spring order (what `F_i += ...` means).
        for m in range(n_masses):
            ax = 0.0
            ay = 0.0
            az = weight
            for e in range(first[m], first[m + 1]):
                s = incident[e]
                if s >= 0:
                    ax += sfx[s]
                    ay += sfy[s]
                    az += sfz[s]
                else:
                    ax -= sfx[~s]
                    ay -= sfy[~s]
                    az -= sfz[~s]
            fx[m] = ax
            fy[m] = ay
            fz[m] = az
        advance(
            step_factor,
            x,
            y,
            z,
            vx,
            vy,
            vz,
            fx,
            fy,
            fz,
            ground_k,
            ground_c,
            friction,
            damping,
            dt,
            terrain_kind,
            terrain,
            contact,
            near,
        )
