"""Variation shared by the built-in strategies: the paper's crossover-and-mutation of two
parents, and a mutant of one. Both draw only from the generator they are given."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from softevo.core.robots.encodings import Encoding
from softevo.core.search import operators
from softevo.core.search.state import Individual

if TYPE_CHECKING:
    from softevo.core.search.settings import SearchSettings


def mate(
    config: SearchSettings,
    encoding: Encoding,
    pair: tuple[Individual, Individual],
    indices: tuple[int, int],
    rng: np.random.Generator,
    children: int = 2,
) -> list[Individual]:
    """Two children of `pair`: with probability `crossover_probability` a two-point crossover
    of each gene segment (a voxel's own real genes cut with its label), else copies; each then
    mutated with probability `mutation_probability`. Parents are named by `indices`. An
    encoding that brings its own operators (`Encoding.variation`; `cppn`: NEAT) breeds them.
    `children=1` leaves out the second child's mutation, the last draws: the first child is
    the same (steady-state keeps one child a birth and draws nothing after it)."""
    if encoding.variation is not None:
        crossed, bred = encoding.variation.mate(config, pair[0].genome, pair[1].genome, rng)
        return [
            Individual(genome, label, _parents(crossed, indices, k))
            for k, (genome, label) in enumerate(bred)
        ]
    first, second = pair
    a, b = np.array(first.genome.discrete), np.array(second.genome.discrete)
    ra, rb = np.array(first.genome.real), np.array(second.genome.real)
    operator = "copy"
    if rng.random() < config.crossover_probability:
        operator = "crossover"
        cut = (0, 0)
        for segment in encoding.segments:
            part = slice(segment.start, segment.stop)
            a[part], b[part], cut = operators.two_point_crossover(a[part], b[part], rng)
        if encoding.voxel_reals:  # a voxel's own genes go with its label: the same cut
            robot = len(ra) - encoding.voxel_reals * encoding.n_discrete
            ra, rb = _cut_with_labels(ra, rb, cut, robot, encoding.n_discrete, rng)
        else:
            ra, rb, _ = operators.two_point_crossover(ra, rb, rng)
    bred = []
    for k, (discrete, real) in enumerate(((a, ra), (b, rb))[:children]):
        label = operator
        if rng.random() < config.mutation_probability:
            label += "+mutation"
            discrete = operators.mutate_discrete(
                discrete, encoding.alphabet, config.mutation_genes, rng
            )
            real = operators.mutate_real(real, encoding.real_bounds, config.mutation_sigma, rng)
        parents = _parents(operator == "crossover", indices, k)
        bred.append(Individual(encoding.genome(discrete, real), label, parents))
    return bred


def mutant(
    config: SearchSettings,
    encoding: Encoding,
    parent: Individual,
    index: int,
    rng: np.random.Generator,
) -> Individual:
    """A mutated copy of `parent` (at least one discrete gene redrawn, real genes stepped; an
    encoding that brings its own operators mutates it itself)."""
    if encoding.variation is not None:
        return Individual(
            encoding.variation.mutate(config, parent.genome, rng), "copy+mutation", (index,)
        )
    genome = parent.genome
    discrete = operators.mutate_discrete(
        np.array(genome.discrete), encoding.alphabet, max(1, config.mutation_genes), rng
    )
    real = operators.mutate_real(
        np.array(genome.real), encoding.real_bounds, config.mutation_sigma, rng
    )
    return Individual(encoding.genome(discrete, real), "copy+mutation", (index,))


def _parents(crossed: bool, indices: tuple[int, int], k: int) -> tuple[int, ...]:
    """A crossed child's parents are both; a copy's, the one it copies."""
    return tuple(int(i) for i in indices) if crossed else (int(indices[k]),)


def _cut_with_labels(
    ra: np.ndarray,
    rb: np.ndarray,
    cut: tuple[int, int],
    robot: int,
    n_voxels: int,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """Crossover of co-design genes: the robot's own `robot` real genes (before the per-voxel
    blocks) by their own two-point cut; every per-voxel block swapped over the labels' cut."""
    ra, rb = ra.copy(), rb.copy()
    ra[:robot], rb[:robot], _ = operators.two_point_crossover(ra[:robot], rb[:robot], rng)
    i, j = cut
    for start in range(robot, len(ra), n_voxels):
        block = slice(start + i, start + j)
        ra[block], rb[block] = rb[block].copy(), ra[block].copy()
    return ra, rb
