"""Variation shared by the built-in strategies: the paper's crossover-and-mutation of two
parents, and a mutant of one; and variation that explores (issue 51). All draw only from the
generator they are given, so a run stays the same for any number of workers.

Exploring variation is for any strategy with options variation 'explore' (`VariationOptions`;
new NSGA-II and AFPO runs get it): every child mutated gene by gene, `mutated_genes` genes
changed on average (1 of the genome's n by default: a rate of 1/n per gene; labels redrawn to
another value, real genes stepped by a Gaussian of `mutation_sigma` x their range), and a child
that repeats a genome already met (the parents' generation, or an earlier child of this one)
re-drawn, up to `REDRAWS` times, instead of being counted as a birth that the cache answers for
free. An encoding with operators of its own (`cppn`: NEAT) breeds with them, its repeats
re-drawn the same way.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial
from typing import TYPE_CHECKING, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from softevo.core.robots.encodings import Encoding
from softevo.core.search import operators
from softevo.core.search.state import Individual

if TYPE_CHECKING:
    from softevo.core.search.settings import SearchSettings


class VariationOptions(BaseModel):
    """How children are made: the options the GA, NSGA-II, AFPO and steady-state share
    (MAP-Elites has its own variation options)."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)

    variation: Literal["paper", "explore"] = Field(
        "paper",
        description="paper: the GA's operators (mutation_probability, mutation_genes), as runs "
        "stored before issue 51; explore (what new nsga2 and afpo runs get): every child mutated "
        "gene by gene, mutated_genes genes on average, and a child repeating a genome already "
        "met re-drawn (docs/evolution.md)",
    )
    mutated_genes: float = Field(
        1.0,
        gt=0,
        le=1000,
        description="explore: genes changed per child on average (a rate of mutated_genes / n "
        "per gene of a genome of n)",
    )


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
        crossed, own = encoding.variation.mate(config, pair[0].genome, pair[1].genome, rng)
        return [
            Individual(genome, label, _parents(crossed, indices, k))
            for k, (genome, label) in enumerate(own)
        ]
    operator, (a, ra), (b, rb) = _crossed(config, encoding, pair, rng)
    bred: list[Individual] = []
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


def _crossed(
    config: SearchSettings,
    encoding: Encoding,
    pair: tuple[Individual, Individual],
    rng: np.random.Generator,
) -> tuple[str, tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """The operator ("crossover" with probability `crossover_probability`, else "copy") and
    the two children's (discrete, real) genes before mutation."""
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
    return operator, (a, ra), (b, rb)


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


#: Tries for a child that repeats a genome already met before it is kept as it is (a
#: population of one genome's neighbours can run out of new ones).
REDRAWS = 10


def gene_rate(encoding: Encoding, mutated_genes: float) -> float:
    """The per-gene chance that makes `mutated_genes` of the genome's genes change on average."""
    genes = int((np.asarray(encoding.alphabet) > 1).sum()) + len(encoding.real_bounds)
    return min(1.0, mutated_genes / max(1, genes))


def _mutated(
    config: SearchSettings,
    encoding: Encoding,
    discrete: np.ndarray,
    real: np.ndarray,
    rate: float,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    discrete = operators.mutate_each(discrete, encoding.alphabet, rate, rng)
    real = operators.mutate_real_each(real, encoding.real_bounds, rate, config.mutation_sigma, rng)
    return discrete, real


def unseen(
    breed: Callable[[], list[Individual]], seen: set[str], redraws: int = REDRAWS
) -> list[Individual]:
    """`breed()`'s children, each one whose genome is in `seen` replaced by the child at its
    place of another `breed()`, up to `redraws` times; `seen` gains every child kept."""
    children = breed()
    for k in range(len(children)):
        tries = 0
        while children[k].genome.hash in seen and tries < redraws:
            children[k] = breed()[k]
            tries += 1
        seen.add(children[k].genome.hash)
    return children


def explore_children(
    config: SearchSettings,
    encoding: Encoding,
    parents: Sequence[Individual],
    mates: np.ndarray,
    count: int,
    mutated_genes: float,
    rng: np.random.Generator,
) -> list[Individual]:
    """`count` children of the pairs `mates` ([K, 2] indices of `parents`): crossover as the
    GA's (`crossover_probability`), then every child mutated gene by gene; repeats re-drawn."""
    seen = {parent.genome.hash for parent in parents}
    rate = gene_rate(encoding, mutated_genes)
    children: list[Individual] = []
    for first, second in mates.reshape(-1, 2):
        pair, indices = (parents[first], parents[second]), (int(first), int(second))
        children.extend(unseen(partial(_pair, config, encoding, pair, indices, rate, rng), seen))
    return children[:count]


def explore_child(
    config: SearchSettings,
    encoding: Encoding,
    pair: tuple[Individual, Individual],
    mutated_genes: float,
    seen: set[str],
    rng: np.random.Generator,
) -> Individual:
    """One child of `pair` (named 0 and 1) by exploring variation, re-drawn while its genome
    is in `seen` (steady-state's birth: one child, its sibling's mutation never drawn)."""
    rate = gene_rate(encoding, mutated_genes)
    breed = partial(_pair, config, encoding, pair, (0, 1), rate, rng, 1)
    return unseen(breed, seen)[0]


def _pair(
    config: SearchSettings,
    encoding: Encoding,
    pair: tuple[Individual, Individual],
    indices: tuple[int, int],
    rate: float,
    rng: np.random.Generator,
    children: int = 2,
) -> list[Individual]:
    if encoding.variation is not None:  # its own operators (cppn: NEAT), as `mate` breeds
        return mate(config, encoding, pair, indices, rng)[:children]
    operator, *genes = _crossed(config, encoding, pair, rng)
    bred: list[Individual] = []
    for k, (discrete, real) in enumerate(genes[:children]):
        discrete, real = _mutated(config, encoding, discrete, real, rate, rng)
        parents = indices if operator == "crossover" else (indices[k],)
        bred.append(Individual(encoding.genome(discrete, real), operator + "+mutation", parents))
    return bred


def explore_mutants(
    config: SearchSettings,
    encoding: Encoding,
    parents: Sequence[Individual],
    chosen: Sequence[int],
    mutated_genes: float,
    rng: np.random.Generator,
) -> list[Individual]:
    """A mutant of each of `parents[i]` for i in `chosen` (gene by gene; repeats re-drawn)."""
    seen = {parent.genome.hash for parent in parents}
    rate = gene_rate(encoding, mutated_genes)
    return [
        unseen(partial(_one_mutant, config, encoding, parents[i], int(i), rate, rng), seen)[0]
        for i in chosen
    ]


def _one_mutant(
    config: SearchSettings,
    encoding: Encoding,
    parent: Individual,
    index: int,
    rate: float,
    rng: np.random.Generator,
) -> list[Individual]:
    return [_mutant(config, encoding, parent, index, rate, rng)]


def _mutant(
    config: SearchSettings,
    encoding: Encoding,
    parent: Individual,
    index: int,
    rate: float,
    rng: np.random.Generator,
) -> Individual:
    if encoding.variation is not None:  # its own operators, as `mutant` mutates
        return mutant(config, encoding, parent, index, rng)
    discrete, real = np.array(parent.genome.discrete), np.array(parent.genome.real)
    discrete, real = _mutated(config, encoding, discrete, real, rate, rng)
    return Individual(encoding.genome(discrete, real), "copy+mutation", (index,))
