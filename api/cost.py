"""What an accepted run or sweep may cost, counted before anything runs: simulated spring-steps
(the springs of the full bounding box x integration steps x the simulations the config can ask
for x what its terrain and objective cost against flat ground, an upper bound) and stored bytes
(every individual's row with its genome, the genomes the run's state holds, and a
quality-diversity archive's elites). Over the
service's budget, the request is refused with both figures and the setting that raises it."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from softevo.core.config import RunConfig
from softevo.core.search.registry import strategy_class
from softevo.core.search.vectors import needs_energy

#: A stored individual's row beyond its genes (ids, hash, operator, parents, times), bytes.
ROW_BYTES = 300
#: An archive elite beyond its genes (cell, fitness, generation, index, keys), bytes, and per
#: descriptor (its cell index and value): a map-elites archive of 8 x 8 paper-voxel elites is
#: about 360 bytes an elite, kept in the run's state.
ELITE_BYTES, ELITE_DESCRIPTOR_BYTES = 60, 30

#: Time of a simulation on each terrain against flat ground, and with the actuators' work
#: measured (objective `efficiency`) against without, rounded up over what was measured:
#: `python bench/cost_factors.py 5 [paper-voxel|quick] [alone]` (8 random robots, least CPU
#: seconds of 5 interleaved rounds; 2026-12-05, 2-core VM) gave efficiency 1.12-1.30x, slope
#: 1.07-1.11x, steps 1.06x, hurdles 1.13-1.16x, rough 1.12-1.24x (amplitude 0.2 to 100), rough
#: with efficiency 1.27-1.40x; whole runs through the service measured efficiency 1.46-1.70x,
#: slope 1.26x and rough at amplitude 100 1.28x (issue 39). The factors multiply.
TERRAIN_COST = {"flat": 1.0, "slope": 1.3, "steps": 1.2, "rough": 1.3, "hurdles": 1.2}
OBJECTIVE_COST = {"efficiency": 1.7}  # the others: 1.0


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


def cost_factor(config: RunConfig) -> float:
    """How much one simulation of this config costs against flat ground scored by speed."""
    terrain = TERRAIN_COST.get(config.sim.terrain.kind, max(TERRAIN_COST.values()))
    if needs_energy(config.objectives):  # the actuators' work measured, as for efficiency
        return terrain * OBJECTIVE_COST["efficiency"]
    return terrain * OBJECTIVE_COST.get(config.objective, 1.0)


def run_cost(config: RunConfig) -> Cost:
    """The most one run can cost: every individual of every generation simulated (with
    `max_simulations`, at most that and the row that passes it; all of them stored), the genomes
    its strategy's state holds (`Strategy.state_genomes`), and with descriptors an archive with
    as many elites as it has cells (or individuals, if fewer)."""
    individuals = config.population * config.generations
    simulated = individuals  # repeats of a genome are stored but not simulated again
    if config.max_simulations is not None:  # the run ends at the row reaching it: a row more
        simulated = min(individuals, config.max_simulations + config.population)
    encoding = config.make_encoding()
    genome_bytes = getattr(encoding, "genome_bytes", None) or (
        2 * len(encoding.alphabet) + 20 * len(encoding.real_bounds) + 60
    )  # an encoding of variable length (cppn) says what a genome of it may take
    elites = min(math.prod(config.bins), individuals) if config.descriptors else 0
    elite_bytes = ELITE_BYTES + ELITE_DESCRIPTOR_BYTES * len(config.descriptors) + genome_bytes
    state = (
        strategy_class(config.algorithm).state_genomes(config.strategy_settings()) * genome_bytes
    )
    simulations = float(box_springs(config.shape)) * config.sim.n_steps * simulated
    return Cost(
        spring_steps=simulations * cost_factor(config),
        stored_bytes=float(individuals) * (ROW_BYTES + genome_bytes) + state + elites * elite_bytes,
    )


def total_cost(configs: Sequence[RunConfig]) -> Cost:
    return sum((run_cost(config) for config in configs), Cost(0.0, 0.0))
