"""The stable time step of a mass-spring lattice, from its stiffest material and smallest mass.

Semi-implicit Euler on an oscillator of angular frequency w with damping ratio zeta (the damping
force taken from the last velocity) is stable while w dt <= 2 (sqrt(1 + zeta^2) - zeta): 2 with
no damping, 0.83 at zeta = 1. The largest w of a lattice is bounded by Gershgorin's theorem: a
mass m whose springs sum to K has w^2 <= (2 K + k_ground) / m. In a solid block a point's 26
springs are 6 edges shared by 4 voxels, 12 face diagonals shared by 2 and 8 body diagonals of one,
56 voxel springs in all, so K <= 56 k_max for every voxel robot of a material set. The step so
derived is sure to be stable and is a conservative one: the true largest w of a solid block is
below this bound.
"""

from __future__ import annotations

import math

#: Voxel springs meeting at one lattice point of a solid block (see the module's docstring).
SPRINGS_AT_A_POINT = 6 * 4 + 12 * 2 + 8


def damped_limit(zeta: float) -> float:
    """The largest stable w dt of semi-implicit Euler at damping ratio `zeta`."""
    return 2.0 * (math.sqrt(1.0 + zeta * zeta) - zeta)


def critical_step(k_max: float, mass: float, ground_k: float, zeta: float) -> float:
    """The critical step (s) of any voxel robot whose springs are at most `k_max` (N/m) per
    voxel, on masses of `mass` (kg), on a ground of `ground_k` (N/m)."""
    omega_sq = (2.0 * SPRINGS_AT_A_POINT * k_max + ground_k) / mass
    if omega_sq <= 0.0:
        return math.inf
    return damped_limit(zeta) / math.sqrt(omega_sq)


def sure_unstable_step(k_max: float, mass: float, zeta: float) -> float:
    """The step (s) past which one spring of `k_max` between two masses of `mass` is unstable:
    that spring's own mode has w^2 = 2 k / m, and a lattice's highest w is at least any of its
    springs' (a Rayleigh quotient), so no robot holding such a spring survives a longer step."""
    omega_sq = 2.0 * k_max / mass
    return math.inf if omega_sq <= 0.0 else damped_limit(zeta) / math.sqrt(omega_sq)


def spring_damping(stiffness: float, mass: float, zeta: float) -> float:
    """The dashpot (N s/m) of a spring between two masses of `mass` at damping ratio `zeta`:
    2 zeta sqrt(k mu), mu = mass / 2 the pair's reduced mass (as Voxelyze's bond zeta)."""
    return 2.0 * zeta * math.sqrt(stiffness * mass / 2.0)
