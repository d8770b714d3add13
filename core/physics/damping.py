"""The kernels' damping in physical units: each spring's dashpot and the ground contact's, from
the ratios to critical damping the settings give (docs/physics.md, "One step")."""

from __future__ import annotations

import math

import numpy as np

from softevo.core.robots.robot import Mechanics
from softevo.core.robots.settings import SimSettings


def ground_damping(sim: SimSettings) -> float:
    """The ground contact's dashpot (N s/m): `contact_damping` of critical for one mass."""
    return 2.0 * sim.contact_damping * math.sqrt(sim.ground_stiffness * sim.mass)


def spring_dashpots(mech: Mechanics) -> np.ndarray:
    """Each spring's dashpot over dt (N/m, `step.spring_damping`), or no array at all where the
    material is undamped (the kernels then take the undamped arithmetic, to the last bit)."""
    sim = mech.sim
    if sim.material_damping == 0.0:
        return np.zeros(0)
    return 2.0 * sim.material_damping * np.sqrt(mech.stiffness * sim.mass / 2.0) / sim.step
