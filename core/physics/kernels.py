"""The numba mass-spring kernels: raw arrays and scalars in, positions out.

Two kernels share one arithmetic, written out identically, so a robot simulated alone and the
same robot in a batch give bit-identical positions:

* `simulate_one`: one robot, structure-of-arrays positions [M]; springs loop in two passes (a
  gather pass that computes spring forces, which the compiler can vectorise, and a scatter pass
  that accumulates them in spring order);
* `simulate_many`: B robots that share one topology (a batch pads absent springs with k = 0 and
  absent masses with a zero step factor), positions [M, B], robot index innermost so every
  operation runs across SIMD lanes.

One step, for every spring s = (i, j) and then every mass m (see docs/physics.md):

    L0   = rest[s] + amp_sin[s] sin(w t) + amp_cos[s] cos(w t),   t = step * dt
    d    = |x_j - x_i|;  f = k[s] (d - L0) / max(d, D_MIN)  ->  F_i += f (x_j - x_i), F_j -= ...
    Fn   = ground_k * max(-z_m, 0);  v += (F + m g e_z + Fn e_z) * h_m   (h_m = dt / m, or 0)
    v_xy *= max(1 - mu Fn h_m / max(|v_xy|, V_MIN), 0)                   (Coulomb, can stick)
    v    *= damping;  x += v dt                                         (semi-implicit Euler)

No fastmath: the arithmetic is plain IEEE double, the same on every worker.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Smallest spring length divided by (guards a collapsed or padding spring against 0 / 0).
D_MIN = 1e-12
#: Smallest horizontal speed divided by in the friction step.
V_MIN = 1e-300

_JIT = {"cache": True, "nogil": True, "error_model": "numpy", "boundscheck": False}


@njit(**_JIT)
def simulate_one(
    x, y, z, vx, vy, vz,  # [M] positions (m), velocities (m/s); updated in place
    step_factor,  # [M] dt / mass, or 0 for a mass that must not move
    spring_a, spring_b,  # [S] int64 mass indices
    stiffness, rest, amp_sin, amp_cos,  # [S] float64
    omega, dt, n_steps, weight, ground_k, friction, damping,
    settle_step, settle_x, settle_y, settle_z,  # positions copied when step == settle_step
    record_every, frames,  # frames [F, 3, M]: positions every record_every steps, and the last
):  # fmt: skip
    n_masses = x.shape[0]
    n_springs = spring_a.shape[0]
    fx = np.empty(n_masses)
    fy = np.empty(n_masses)
    fz = np.empty(n_masses)
    sfx = np.empty(n_springs)
    sfy = np.empty(n_springs)
    sfz = np.empty(n_springs)
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
        for s in range(n_springs):
            i = spring_a[s]
            j = spring_b[s]
            dx = x[j] - x[i]
            dy = y[j] - y[i]
            dz = z[j] - z[i]
            d = math.sqrt(dx * dx + dy * dy + dz * dz)
            length0 = rest[s] + amp_sin[s] * sin_t + amp_cos[s] * cos_t
            f = stiffness[s] * (d - length0) / max(d, D_MIN)
            sfx[s] = f * dx
            sfy[s] = f * dy
            sfz[s] = f * dz
        for m in range(n_masses):
            fx[m] = 0.0
            fy[m] = 0.0
            fz[m] = weight
        for s in range(n_springs):
            i = spring_a[s]
            j = spring_b[s]
            fx[i] += sfx[s]
            fy[i] += sfy[s]
            fz[i] += sfz[s]
            fx[j] -= sfx[s]
            fy[j] -= sfy[s]
            fz[j] -= sfz[s]
        for m in range(n_masses):
            h = step_factor[m]
            normal = ground_k * max(-z[m], 0.0)
            ux = vx[m] + fx[m] * h
            uy = vy[m] + fy[m] * h
            uz = vz[m] + (fz[m] + normal) * h
            speed = math.sqrt(ux * ux + uy * uy)
            slip = max(1.0 - friction * normal * h / max(speed, V_MIN), 0.0)
            vx[m] = ux * slip * damping
            vy[m] = uy * slip * damping
            vz[m] = uz * damping
            x[m] += vx[m] * dt
            y[m] += vy[m] * dt
            z[m] += vz[m] * dt


@njit(**_JIT)
def simulate_many(
    x, y, z, vx, vy, vz,  # [M, B] positions, velocities; updated in place
    step_factor,  # [M, B] dt / mass, or 0 for padding masses
    spring_a, spring_b,  # [S] int64, shared by all robots of the batch
    stiffness, rest, amp_sin, amp_cos,  # [S, B] float64 (k = 0 for padding springs)
    omega, dt, n_steps, weight, ground_k, friction, damping,
    settle_step, settle_x, settle_y, settle_z,  # [M, B]
):  # fmt: skip
    n_masses, n_robots = x.shape
    n_springs = spring_a.shape[0]
    fx = np.empty((n_masses, n_robots))
    fy = np.empty((n_masses, n_robots))
    fz = np.empty((n_masses, n_robots))
    for step in range(n_steps + 1):
        if step == settle_step:
            settle_x[:, :] = x
            settle_y[:, :] = y
            settle_z[:, :] = z
        if step == n_steps:
            break
        t = step * dt
        sin_t = math.sin(omega * t)
        cos_t = math.cos(omega * t)
        fx[:, :] = 0.0
        fy[:, :] = 0.0
        fz[:, :] = weight
        for s in range(n_springs):
            i = spring_a[s]
            j = spring_b[s]
            xi, yi, zi, xj, yj, zj = x[i], y[i], z[i], x[j], y[j], z[j]
            fxi, fyi, fzi, fxj, fyj, fzj = fx[i], fy[i], fz[i], fx[j], fy[j], fz[j]
            k, r0, a_s, a_c = stiffness[s], rest[s], amp_sin[s], amp_cos[s]
            for r in range(n_robots):
                dx = xj[r] - xi[r]
                dy = yj[r] - yi[r]
                dz = zj[r] - zi[r]
                d = math.sqrt(dx * dx + dy * dy + dz * dz)
                length0 = r0[r] + a_s[r] * sin_t + a_c[r] * cos_t
                f = k[r] * (d - length0) / max(d, D_MIN)
                px = f * dx
                py = f * dy
                pz = f * dz
                fxi[r] += px
                fyi[r] += py
                fzi[r] += pz
                fxj[r] -= px
                fyj[r] -= py
                fzj[r] -= pz
        for m in range(n_masses):
            hm, xm, ym, zm = step_factor[m], x[m], y[m], z[m]
            vxm, vym, vzm, fxm, fym, fzm = vx[m], vy[m], vz[m], fx[m], fy[m], fz[m]
            for r in range(n_robots):
                h = hm[r]
                normal = ground_k * max(-zm[r], 0.0)
                ux = vxm[r] + fxm[r] * h
                uy = vym[r] + fym[r] * h
                uz = vzm[r] + (fzm[r] + normal) * h
                speed = math.sqrt(ux * ux + uy * uy)
                slip = max(1.0 - friction * normal * h / max(speed, V_MIN), 0.0)
                vxm[r] = ux * slip * damping
                vym[r] = uy * slip * damping
                vzm[r] = uz * damping
                xm[r] += vxm[r] * dt
                ym[r] += vym[r] * dt
                zm[r] += vzm[r] * dt
