"""The numba mass-spring kernels: raw arrays and scalars in, positions out.

Two kernels share one arithmetic, so a robot simulated alone and the same robot in a batch give
bit-identical positions:

* `simulate_one`: one robot, structure-of-arrays positions [M], springs as a list of mass pairs.
  Each step gathers the spring vectors x_j - x_i (indexed loads), computes every spring's force
  in a loop the compiler vectorises (sqrt and divide across SIMD lanes), then sums the forces on
  each mass from a list of its springs, in spring order, in registers.
* `simulate_many`: B robots on one box of lattice points (see below), positions [P, B] with the
  robot index innermost, so every loop runs over P * B contiguous numbers across SIMD lanes.

One step, for every spring s = (i, j) and then every mass m (see docs/physics.md):

    L0   = rest[s] + amp_sin[s] sin(w t) + amp_cos[s] cos(w t),   t = step * dt
    d    = |x_j - x_i|;  f = k[s] (d - L0) / max(d, D_MIN)  ->  F_i += f (x_j - x_i), F_j -= ...
    Fn   = ground_k * max(-z_m, 0);  v += (F + m g e_z + Fn e_z) * h_m   (h_m = dt / m, or 0)
    v_xy *= max(1 - mu Fn h_m / max(|v_xy|, V_MIN), 0)                   (Coulomb, can stick)
    v    *= damping;  x += v dt                                         (semi-implicit Euler)

F_m starts at (0, 0, m g) and takes its spring terms in spring order. No fastmath: the arithmetic
is plain IEEE double (no reassociation, no fused multiply-add), the same on every worker.

**The batched layout.** `simulate_many` numbers the lattice points of a box (x fastest, then y, then
z, like `softevo.core.robots.lattice`) and stores each spring in a *slot* (q, p): the spring from
point p to point p + offsets[q], where `offsets` are the distinct positive index offsets of a
point's 26 neighbours in the box, ascending. A slot that is no spring of robot r (two points that
are not neighbours, across the edge of the box, or a spring robot r lacks) has k = 0 in lane r; a
point robot r lacks has a zero step factor, so it never moves. Then one direction q is one flat loop
over (P - offsets[q]) * B contiguous numbers with no index arrays, and the sums are two flat loops
per direction and component. This is 1.5 to 4 times as fast as walking the springs one by one with a
short loop over the robots inside (BENCHMARKS.md): that inner loop ran only a few vector iterations
per spring, each behind runtime checks that its arrays do not overlap, and with 32 robots its
working set outgrew the L2 cache. The price is wasted work on k = 0 slots (a solid 4x4x4 block has
1384 slots for 1036 springs). Batches of 4 to 8 robots run fastest.

**Why the two kernels agree bit for bit.** Per robot, both compute each spring's force with the
same operations in the same order. Springs are sorted by (first mass, second mass), so a mass m
takes `-=` from its springs (a, m) by a ascending, then `+=` from its springs (m, b) by b
ascending. `simulate_many` applies to each point all `-=` terms by descending offset (a = p -
offset ascending), then all `+=` terms by ascending offset (b = p + offset ascending): the same
sequence. A k = 0 slot adds a signed zero, which changes nothing: a sum that starts at +0 or at
the (nonzero) weight can never become -0, and x + 0 = x - 0 = x for every other x. This needs
finite positions; a robot that blew up is reported unstable either way.
"""

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


@njit(**JIT)
def simulate_many(
    x,
    y,
    z,
    vx,
    vy,
    vz,  # [P, B] positions, velocities of the box's points; updated in place
    step_factor,  # [P, B] dt / mass, or 0 for a point the robot lacks
    offsets,  # [D] int64, ascending: slot (q, p) is the spring from point p to p + offsets[q]
    stiffness,
    rest,
    amp_sin,
    amp_cos,  # [D, P, B] float64, k = 0 where a slot is no spring
    damp,  # [D, P, B] each slot's dashpot over dt (N/m), or [0, 0, 0]: no material damping
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
    settle_z,  # [P, B]
    energy,  # [D, P, B] actuator work of each slot from settle_step on (J), or [0, 0, 0]
):
    n_points, n_robots = x.shape
    n = n_points * n_robots
    n_dir = offsets.shape[0]
    # Flat views, point-major and robot innermost: point p of robot r is element p * B + r, so
    # the point p + offset of the same robot is offset * B elements further on.
    x, y, z = x.reshape(n), y.reshape(n), z.reshape(n)
    vx, vy, vz = vx.reshape(n), vy.reshape(n), vz.reshape(n)
    step_factor = step_factor.reshape(n)
    stiffness = stiffness.reshape(n_dir, n)
    rest = rest.reshape(n_dir, n)
    amp_sin = amp_sin.reshape(n_dir, n)
    amp_cos = amp_cos.reshape(n_dir, n)
    measure = energy.shape[0] > 0
    damped = damp.shape[0] > 0
    damp = damp.reshape(damp.shape[0], damp.shape[1] * damp.shape[2])
    last = np.zeros(damp.shape)  # each slot's length at the last step
    for q in range(last.shape[0]):
        shift = offsets[q] * n_robots
        for e in range(n - shift):
            last[q, e] = length(x[e + shift] - x[e], y[e + shift] - y[e], z[e + shift] - z[e])
    energy = energy.reshape(energy.shape[0], energy.shape[1] * energy.shape[2])
    # Spring force components of every slot, then the force on every point.
    sfx = np.empty((n_dir, n))
    sfy = np.empty((n_dir, n))
    sfz = np.empty((n_dir, n))
    fx = np.empty(n)
    fy = np.empty(n)
    fz = np.empty(n)
    contact = contact_scratch(n)  # terrain contact scratch (`contact_pass`)
    near = np.empty(n, dtype=np.int64)
    for step in range(n_steps + 1):
        if step == settle_step:
            settle_x[:, :] = x.reshape(n_points, n_robots)
            settle_y[:, :] = y.reshape(n_points, n_robots)
            settle_z[:, :] = z.reshape(n_points, n_robots)
        if step == n_steps:
            break
        t = step * dt
        sin_t = math.sin(omega * t)
        cos_t = math.cos(omega * t)
        # Gather: one flat loop per direction over the slots that fit in the box. Separate
        # views of the two ends keep every index a plain loop counter, so the loop vectorises.
        for q in range(n_dir):
            shift = offsets[q] * n_robots
            count = n - shift
            if count <= 0:
                continue
            xi, yi, zi = x[:count], y[:count], z[:count]
            xj, yj, zj = x[shift:], y[shift:], z[shift:]
            k, r0, a_s, a_c = stiffness[q], rest[q], amp_sin[q], amp_cos[q]
            px, py, pz = sfx[q], sfy[q], sfz[q]
            if measure and step >= settle_step:
                work = energy[q]
                for e in range(count):
                    work[e] += dt * actuator_power(
                        xj[e] - xi[e],
                        yj[e] - yi[e],
                        zj[e] - zi[e],
                        k[e],
                        r0[e],
                        a_s[e],
                        a_c[e],
                        sin_t,
                        cos_t,
                        omega,
                    )
            if damped:
                c, lq = damp[q], last[q]
                for e in range(count):
                    px[e], py[e], pz[e], lq[e] = damped_spring_force(
                        xj[e] - xi[e],
                        yj[e] - yi[e],
                        zj[e] - zi[e],
                        k[e],
                        r0[e],
                        a_s[e],
                        a_c[e],
                        sin_t,
                        cos_t,
                        c[e],
                        lq[e],
                    )
                continue
            for e in range(count):
                px[e], py[e], pz[e] = spring_force(
                    xj[e] - xi[e],
                    yj[e] - yi[e],
                    zj[e] - zi[e],
                    k[e],
                    r0[e],
                    a_s[e],
                    a_c[e],
                    sin_t,
                    cos_t,
                )
        # Scatter in each point's spring order: the second ends (-=) by descending offset, then
        # the first ends (+=) by ascending offset. One loop per component: each has a single
        # store stream and a single load stream, so it vectorises with one cheap overlap check.
        for e in range(n):
            fx[e] = 0.0
            fy[e] = 0.0
            fz[e] = weight
        for q in range(n_dir - 1, -1, -1):
            shift = offsets[q] * n_robots
            count = n - shift
            if count <= 0:
                continue
            gx, gy, gz = fx[shift:], fy[shift:], fz[shift:]
            px, py, pz = sfx[q], sfy[q], sfz[q]
            for e in range(count):
                gx[e] -= px[e]
            for e in range(count):
                gy[e] -= py[e]
            for e in range(count):
                gz[e] -= pz[e]
        for q in range(n_dir):
            count = n - offsets[q] * n_robots
            if count <= 0:
                continue
            px, py, pz = sfx[q], sfy[q], sfz[q]
            for e in range(count):
                fx[e] += px[e]
            for e in range(count):
                fy[e] += py[e]
            for e in range(count):
                fz[e] += pz[e]
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
