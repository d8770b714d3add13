"""What an accepted run or sweep may cost, counted before anything runs: simulated spring-steps
(the springs of the full bounding box x integration steps x the simulations the config can ask
for, an upper bound) and stored bytes (every individual's row with its genome). Over the
service's budget, the request is refused with both figures and the setting that raises it."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from softevo.core.config import RunConfig

#: A stored individual's row beyond its genes (ids, hash, operator, parents, times), bytes.
ROW_BYTES = 300


def box_springs(shape: tuple[int, int, int]) -> int:
    """Springs of a full box of voxels (shared edges and faces once): 12 edges, 12 face
    diagonals and 4 body diagonals a voxel before sharing (a 4x4x4 box has 1036)."""
    nx, ny, nz = shape
    edges = nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz
    faces = 2 * (nx * ny * (nz + 1) + nx * (ny + 1) * nz + (nx + 1) * ny * nz)
    return edges + faces + 4 * nx * ny * nz


@dataclass(frozen=True)
class Cost:
    spring_steps: float
    stored_bytes: float

    def __add__(self, other: Cost) -> Cost:
        return Cost(self.spring_steps + other.spring_steps, self.stored_bytes + other.stored_bytes)


def run_cost(config: RunConfig) -> Cost:
    """The most one run can cost: every individual of every generation simulated."""
    individuals = config.population * config.generations
    encoding = config.make_encoding()
    genome_bytes = 2 * len(encoding.alphabet) + 20 * len(encoding.real_bounds) + 60
    return Cost(
        spring_steps=float(box_springs(config.shape)) * config.sim.n_steps * individuals,
        stored_bytes=float(individuals) * (ROW_BYTES + genome_bytes),
    )


def total_cost(configs: Sequence[RunConfig]) -> Cost:
    return sum((run_cost(config) for config in configs), Cost(0.0, 0.0))
