"""One spring's arithmetic, shared by both kernels (`kernels`), so every spring's force is the
same operations in either: its length, its force with and without a dashpot, and its actuator's
power. Like `contact`, numba's cache of the kernels is keyed on kernels.py alone: after editing
this module, touch kernels.py so they are compiled again."""

from __future__ import annotations

import math

from numba import njit

from softevo.core.physics.jit import JIT

#: Smallest spring length divided by (guards a collapsed or padding spring against 0 / 0).
D_MIN = 1e-12


@njit(inline="always", **JIT)
def length(dx, dy, dz):
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(inline="always", **JIT)
def spring_force(dx, dy, dz, k, rest, amp_sin, amp_cos, sin_t, cos_t):
    """Force f (x_j - x_i) on the first end of a spring with vector (dx, dy, dz) = x_j - x_i.

    Shared by both kernels, so every spring's force is the same arithmetic in either.
    """
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    length0 = rest + amp_sin * sin_t + amp_cos * cos_t
    f = k * (d - length0) / max(d, D_MIN)
    return f * dx, f * dy, f * dz


@njit(inline="always", **JIT)
def damped_spring_force(dx, dy, dz, k, rest, amp_sin, amp_cos, sin_t, cos_t, damp, last):
    """`spring_force` with a dashpot in parallel: `damp` (N s/m over dt) times the change of the
    spring's length since the last step, (d - last) / dt, which semi-implicit Euler makes the
    relative velocity along the spring. Returns the force and the length d."""
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    length0 = rest + amp_sin * sin_t + amp_cos * cos_t
    f = (k * (d - length0) + damp * (d - last)) / max(d, D_MIN)
    return f * dx, f * dy, f * dz, d


@njit(inline="always", **JIT)
def actuator_power(dx, dy, dz, k, rest, amp_sin, amp_cos, sin_t, cos_t, omega):
    """|T dL0/dt| (W): the rate at which a spring's actuator works against its tension T."""
    d = math.sqrt(dx * dx + dy * dy + dz * dz)
    length0 = rest + amp_sin * sin_t + amp_cos * cos_t
    return abs(k * (d - length0) * (omega * (amp_sin * cos_t - amp_cos * sin_t)))
