"""The mass-spring physics engine: numba kernels and the functions that validate and call them."""

from softevo.core.physics.results import SimResult, Trajectory
from softevo.core.physics.simulate import simulate, simulate_batch

__all__ = ["SimResult", "Trajectory", "simulate", "simulate_batch"]
