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

**Why the two kernels agree bit for bit.** Per robot, both compute each spring's force with the
same operations in the same order. Springs are sorted by (first mass, second mass), so a mass m
takes `-=` from its springs (a, m) by a ascending, then `+=` from its springs (m, b) by b
ascending. `simulate_many` applies to each point all `-=` terms by descending offset (a = p -
offset ascending), then all `+=` terms by ascending offset (b = p + offset ascending): the same
sequence. A k = 0 slot adds a signed zero, which changes nothing: a sum that starts at +0 or at
the (nonzero) weight can never become -0, and x + 0 = x - 0 = x for every other x. This needs
finite positions; a robot that blew up is reported unstable either way.

They live in `kernel_one` and `kernel_many`; this module names both.
"""

from softevo.core.physics.kernel_many import simulate_many
from softevo.core.physics.kernel_one import simulate_one

__all__ = ["simulate_many", "simulate_one"]
