"""The genetic algorithm as ask/tell on explicit state.

`ask(state)` gives the current generation's individuals, `tell(state, individuals, fitness)` takes
their fitness (NaN for a failed evaluation) and returns the next state; both are pure. Generation
g is bred from generation g-1 and its fitness with a generator seeded by (seed, g) alone, so it
can be regenerated exactly from the run's seed and the stored population of g-1, and the whole
state round-trips through JSON.

One generation (g > 0), with P the population size:

1. Survivors: `grouped` selection keeps the best `survival` fraction of each of `groups` random
   groups (the paper); `tournament` and `roulette` keep only the best individual, if `elitism`.
2. Immigrants: round(`immigrants` * P) new random genomes.
3. Children fill the rest, in pairs: two parents (uniform among the survivors for `grouped`, by
   tournament or roulette wheel otherwise); with probability `crossover_probability` a two-point
   crossover of each gene segment, else copies; each child is mutated with probability
   `mutation_probability` (`mutation_genes` discrete genes redrawn to new values, real genes a
   bounded Gaussian step of `mutation_sigma` times their range).
4. With `elitism`, the best individual of g-1 is always among the survivors, so best-so-far never
   falls. (Grouped truncation keeps each group's best, hence always the overall best.)

Two baselines share the machinery (`algorithm`), so they run through the same service, cache and
accounting: `random` search (P new random genomes every generation) and `hillclimb` (the best of
g-1 and P-1 mutants of it). So does quality-diversity: `map-elites` breeds from an archive
(`softevo.core.ga.archive`) that keeps the fittest robot of every cell of its `descriptors`;
with descriptors, any other algorithm keeps the same archive beside it, for comparison.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from softevo.core.encodings import Encoding
from softevo.core.ga import operators
from softevo.core.ga.archive import Archive
from softevo.core.ga.descriptors import CATALOGUE, describe
from softevo.core.ga.state import GAState, Individual, generation_rng
from softevo.core.ga.stats import GenerationStats, generation_stats
from softevo.core.limits import MAX_ARCHIVE_CELLS, MAX_DESCRIPTORS

__all__ = ["GAConfig", "GAState", "GeneticAlgorithm", "Individual", "generation_rng"]


class GAConfig(BaseModel):
    """Every setting of the genetic algorithm; defaults are the paper's phase 3 (`paper-voxel`)."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)

    algorithm: Literal["ga", "random", "hillclimb", "map-elites"] = Field(
        "ga",
        description="ga: the genetic algorithm below; random: P new random genomes every "
        "generation (random search); hillclimb: the best of the last generation and P-1 "
        "mutants of it (a (1+lambda) hill climber); map-elites: quality-diversity, parents "
        "drawn from an archive that keeps the best robot of every cell of `descriptors` x "
        "`bins`, children by the GA's crossover and mutation, plus immigrants.",
    )
    descriptors: tuple[str, ...] = Field(
        (),
        description="quality-diversity descriptors (softevo.core.ga.descriptors: voxels, "
        "actuated, soft, height from the body; heading, in degrees, measured by the "
        "simulation); required by map-elites, and with any other algorithm an "
        "archive is kept beside it for comparison",
    )
    bins: tuple[int, ...] = Field((), description="cells along each descriptor's range")
    population: int = Field(25, ge=2, le=10_000)
    generations: int = Field(100, ge=1, le=100_000)
    selection: Literal["grouped", "tournament", "roulette"] = "grouped"
    groups: int = Field(5, ge=1, le=1000, description="groups of grouped truncation")
    survival: float = Field(0.5, gt=0, le=1, description="fraction kept per group")
    tournament_size: int = Field(3, ge=1, le=100)
    crossover_probability: float = Field(1.0, ge=0, le=1)
    mutation_probability: float = Field(0.02, ge=0, le=1, description="fraction of children")
    mutation_genes: int = Field(2, ge=0, le=100_000, description="discrete genes per mutation")
    mutation_sigma: float = Field(0.1, ge=0, le=10, description="real-gene step / range")
    immigrants: float = Field(0.12, ge=0, le=1, description="fraction of P, each generation")
    elitism: bool = True

    @field_validator("descriptors", "bins", mode="before")
    @classmethod
    def _tuple(cls, value: Any) -> Any:
        return tuple(value) if isinstance(value, list) else value

    @model_validator(mode="after")
    def _archive(self) -> GAConfig:
        if self.algorithm == "map-elites" and not self.descriptors:
            raise ValueError("descriptors: map-elites needs at least one descriptor")
        unknown = [name for name in self.descriptors if name not in CATALOGUE]
        if unknown:
            raise ValueError(f"descriptors: unknown {unknown} (known: {', '.join(CATALOGUE)})")
        if len(set(self.descriptors)) != len(self.descriptors):
            raise ValueError(f"descriptors: each at most once, got {list(self.descriptors)}")
        if len(self.descriptors) > MAX_DESCRIPTORS:
            raise ValueError(f"descriptors: at most {MAX_DESCRIPTORS}, got {len(self.descriptors)}")
        if len(self.bins) != len(self.descriptors):
            raise ValueError(
                f"bins: one count per descriptor, got {len(self.bins)} for "
                f"{len(self.descriptors)} descriptors"
            )
        if any(b < 1 for b in self.bins) or math.prod(self.bins) > MAX_ARCHIVE_CELLS:
            raise ValueError(
                f"bins: each at least 1 and at most {MAX_ARCHIVE_CELLS} cells in all, got "
                f"{list(self.bins)} ({math.prod(self.bins)} cells)"
            )
        return self

    @model_validator(mode="after")
    def _room_for_children(self) -> GAConfig:
        if self.algorithm in ("ga", "map-elites") and self.n_immigrants >= self.population:
            raise ValueError(
                f"immigrants: {self.immigrants} of {self.population} leaves no room for "
                "survivors and children"
            )
        return self

    @property
    def n_immigrants(self) -> int:
        return math.floor(self.immigrants * self.population + 0.5)


class GeneticAlgorithm:
    """Pure ask/tell: `ask(state)` breeds a generation, `tell(state, individuals, fitness)`
    returns the next state; neither changes the state it is given, so whoever holds the state
    (`softevo run`, the service's coordinator) decides when it becomes the current one."""

    def __init__(self, config: GAConfig, encoding: Encoding) -> None:
        self.config = config
        self.encoding = encoding

    def start(self, seed: int) -> GAState:
        return GAState(seed=seed)

    def done(self, state: GAState) -> bool:
        return state.generation >= self.config.generations

    def ask(self, state: GAState) -> list[Individual]:
        """The individuals of `state`'s current generation (always the same for one state)."""
        if self.done(state):
            raise RuntimeError(f"the run has finished its {self.config.generations} generations")
        if state.current is not None:
            return list(state.current)
        return self._breed(state)

    def tell(
        self,
        state: GAState,
        individuals: list[Individual],
        fitness: np.ndarray | list[float],
        *,
        measures: Sequence[Mapping[str, float]] | None = None,
        heading: np.ndarray | list[float] | None = None,
        **counts: int,
    ) -> tuple[GAState, GenerationStats]:
        """The state after `individuals` (what `ask(state)` gave) scored `fitness` (NaN =
        failed), and the generation's statistics; `measures` is each one's record of measures
        (name -> value, NaN or missing = unknown), which behavioural descriptors read;
        `counts` (evaluations, saved, failed, ...) are stored with the statistics."""
        values = np.asarray(fitness, dtype=np.float64)
        if values.shape != (len(individuals),):
            raise ValueError(
                f"expected {len(individuals)} fitness values, got shape {values.shape}"
            )
        best = state.best
        finite = np.isfinite(values)
        if finite.any():
            index = int(np.nanargmax(np.where(finite, values, -np.inf)))
            if best is None or values[index] > best[1]:
                best = (individuals[index].genome, float(values[index]), state.generation)
        best_so_far = best[1] if best is not None else math.nan
        if measures is None:
            directions = [math.nan] * len(individuals) if heading is None else list(heading)
            measures = [{"heading": float(direction)} for direction in directions]
        archive = self._archive(state, individuals, values, measures)
        stats = generation_stats(
            state.generation,
            values,
            [individual.genome for individual in individuals],
            best_so_far,
            **counts,
        )
        if archive is not None:
            stats = replace(stats, coverage=archive.coverage, qd_score=archive.qd_score)
        following = GAState(
            seed=state.seed,
            generation=state.generation + 1,
            current=None,
            previous=list(individuals),
            previous_fitness=values.tolist(),
            best=best,
            history=[*state.history, stats],
            archive=archive,
        )
        return following, stats

    def _archive(
        self,
        state: GAState,
        individuals: list[Individual],
        fitness: np.ndarray,
        measures: Sequence[Mapping[str, float]],
    ) -> Archive | None:
        """The archive after this generation (None for a run without descriptors): each robot
        that did not fail is offered to the cell its descriptors (of its body, and its
        measures) fall in."""
        config = self.config
        if not config.descriptors:
            return None
        archive = state.archive or Archive(config.descriptors, config.bins)
        archive = archive.copy()
        box = self.encoding.shape
        measured = zip(individuals, fitness, measures, strict=True)
        for index, (individual, value, record) in enumerate(measured):
            if math.isfinite(value):
                values = describe(config.descriptors, individual.genome.discrete, box, record)
                archive.add(values, float(value), state.generation, index, individual.genome)
        return archive

    def _breed(self, state: GAState) -> list[Individual]:
        config, encoding = self.config, self.encoding
        rng = generation_rng(state.seed, state.generation)
        if state.generation == 0 or state.previous is None or state.previous_fitness is None:
            return [Individual(encoding.random(rng), "random") for _ in range(config.population)]
        if config.algorithm == "random":
            return [Individual(encoding.random(rng), "random") for _ in range(config.population)]
        if config.algorithm == "map-elites":
            return self._from_archive(state.archive, rng)
        parents = state.previous
        fitness = np.asarray(state.previous_fitness, dtype=np.float64)
        if config.algorithm == "hillclimb":
            return self._climb(parents, fitness, rng)
        if config.selection == "grouped":
            survivors = operators.grouped_truncation(fitness, config.groups, config.survival, rng)
        elif config.elitism:
            survivors = operators.rank_order(fitness)[:1]
        else:
            survivors = np.empty(0, dtype=np.int64)
        survivors = survivors[: config.population - config.n_immigrants]
        n_children = config.population - len(survivors) - config.n_immigrants
        n_parents = 2 * math.ceil(n_children / 2)
        if config.selection == "grouped":
            mates = survivors[rng.integers(0, len(survivors), size=n_parents)]
        elif config.selection == "tournament":
            mates = operators.tournament(fitness, n_parents, config.tournament_size, rng)
        else:
            mates = operators.roulette(fitness, n_parents, rng)
        children: list[Individual] = []
        for first, second in mates.reshape(-1, 2):
            children.extend(self._mate(parents[first], parents[second], (first, second), rng))
        return [
            *(Individual(parents[i].genome, "survivor", (int(i),)) for i in survivors),
            *children[:n_children],
            *(Individual(encoding.random(rng), "immigrant") for _ in range(config.n_immigrants)),
        ]

    def _from_archive(self, archive: Archive | None, rng: np.random.Generator) -> list[Individual]:
        """MAP-Elites: children of pairs of elites drawn uniformly from the archive, by the GA's
        crossover and mutation, then immigrants. Children carry no parent indices (their
        parents are elites of any generation); their operator says `elite-...`."""
        config, encoding = self.config, self.encoding
        elites = archive.ordered() if archive else []
        if not elites:  # nothing survived to breed from: start again at random
            return [Individual(encoding.random(rng), "random") for _ in range(config.population)]
        n_children = config.population - config.n_immigrants
        mates = rng.integers(0, len(elites), size=2 * math.ceil(n_children / 2))
        children: list[Individual] = []
        for first, second in mates.reshape(-1, 2):
            a, b = (Individual(elites[i].genome, "elite") for i in (first, second))
            for child in self._mate(a, b, (int(first), int(second)), rng):
                children.append(Individual(child.genome, f"elite-{child.operator}"))
        return [
            *children[:n_children],
            *(Individual(encoding.random(rng), "immigrant") for _ in range(config.n_immigrants)),
        ]

    def _climb(
        self, parents: list[Individual], fitness: np.ndarray, rng: np.random.Generator
    ) -> list[Individual]:
        """The best of the last generation (so the best so far) and P-1 mutants of it, every
        one mutated with the GA's mutation (`mutation_genes`, `mutation_sigma`)."""
        config, encoding = self.config, self.encoding
        best = int(operators.rank_order(fitness)[0])
        parent = parents[best].genome
        climbers = [Individual(parent, "survivor", (best,))]
        for _ in range(config.population - 1):
            discrete = operators.mutate_discrete(
                np.array(parent.discrete), encoding.alphabet, max(1, config.mutation_genes), rng
            )
            real = operators.mutate_real(
                np.array(parent.real), encoding.real_bounds, config.mutation_sigma, rng
            )
            climbers.append(Individual(encoding.genome(discrete, real), "copy+mutation", (best,)))
        return climbers

    def _mate(
        self,
        first: Individual,
        second: Individual,
        indices: tuple[int, int],
        rng: np.random.Generator,
    ) -> list[Individual]:
        config, encoding = self.config, self.encoding
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
        children = []
        for k, (discrete, real) in enumerate(((a, ra), (b, rb))):
            label = operator
            if rng.random() < config.mutation_probability:
                label += "+mutation"
                discrete = operators.mutate_discrete(
                    discrete, encoding.alphabet, config.mutation_genes, rng
                )
                real = operators.mutate_real(real, encoding.real_bounds, config.mutation_sigma, rng)
            parents = (
                tuple(int(i) for i in indices) if operator == "crossover" else (int(indices[k]),)
            )
            children.append(Individual(encoding.genome(discrete, real), label, parents))
        return children


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
