"""One step's contact, friction, global damping and semi-implicit Euler update of every mass,
shared by both kernels (`kernels`), so they integrate identically. Like `contact`, numba's
cache of the kernels is keyed on kernels.py alone: after editing this module, touch kernels.py."""

from __future__ import annotations

import math

from numba import njit

from softevo.core.physics.contact import contact_pass
from softevo.core.physics.jit import JIT

#: Smallest horizontal speed divided by in the friction step.
V_MIN = 1e-300


@njit(inline="always", **JIT)
def _normal_force(ground_k, ground_c, depth, approach):
    """The ground's push (N) on a point `depth` (m) under its surface, moving into it at
    `approach` (m/s): a penalty spring and, in contact only, a dashpot, never pulling."""
    normal = ground_k * max(depth, 0.0)
    if ground_c > 0.0 and normal > 0.0:
        normal = max(normal + ground_c * approach, 0.0)
    return normal


@njit(inline="always", **JIT)
def _integrate(
    step_factor, x, y, z, vx, vy, vz, fx, fy, fz, ground_k, ground_c, friction, damping, dt
):
    """Ground contact, friction, damping and the semi-implicit Euler update of every mass.

    All arrays are 1-D and the same length; `fz` already holds the weight. Shared by both kernels,
    so they integrate identically.
    """
    for m in range(x.shape[0]):
        h = step_factor[m]
        normal = _normal_force(ground_k, ground_c, -z[m], -vz[m])
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


@njit(inline="always", **JIT)
def _integrate_terrain(
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
    kind,
    tp,
    contact,
    near,
):
    """`_integrate` on any terrain: the penalty force along the surface normal, Coulomb
    friction against the velocity's part in the tangent plane (`contact` and `near`: scratch
    for `contact_pass`)."""
    contact_pass(kind, tp, x, y, z, step_factor, contact, near)
    depth, nx, ny, nz = contact[0], contact[1], contact[2], contact[3]
    for m in range(x.shape[0]):
        h = step_factor[m]
        normal = ground_k * depth[m]
        if ground_c > 0.0 and normal > 0.0:
            into = -(vx[m] * nx[m] + vy[m] * ny[m] + vz[m] * nz[m])
            normal = _normal_force(ground_k, ground_c, depth[m], into)
        ux = vx[m] + (fx[m] + normal * nx[m]) * h
        uy = vy[m] + (fy[m] + normal * ny[m]) * h
        uz = vz[m] + (fz[m] + normal * nz[m]) * h
        along = ux * nx[m] + uy * ny[m] + uz * nz[m]
        tx = ux - along * nx[m]
        ty = uy - along * ny[m]
        tz = uz - along * nz[m]
        speed = math.sqrt(tx * tx + ty * ty + tz * tz)
        slip = max(1.0 - friction * normal * h / max(speed, V_MIN), 0.0)
        vx[m] = (tx * slip + along * nx[m]) * damping
        vy[m] = (ty * slip + along * ny[m]) * damping
        vz[m] = (tz * slip + along * nz[m]) * damping
        x[m] += vx[m] * dt
        y[m] += vy[m] * dt
        z[m] += vz[m] * dt


@njit(inline="always", **JIT)
def advance(
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
    kind,
    tp,
    contact,
    near,
):
    """One step's contact and integration for both kernels: the flat ground's original
    arithmetic (`_integrate`, to the last bit) or any other terrain's."""
    if kind == 0:
        _integrate(
            step_factor, x, y, z, vx, vy, vz, fx, fy, fz, ground_k, ground_c, friction, damping, dt
        )
    else:
        _integrate_terrain(
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
            kind,
            tp,
            contact,
            near,
        )
