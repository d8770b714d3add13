"""`map-elites`: quality-diversity. Parents are drawn from an archive that keeps the fittest
robot of every cell of `descriptors` x `bins` (`softevo.core.search.archive`), so the run keeps the
best of every kind of body instead of one kind.

How children are made is this strategy's own `options` (`MapElitesOptions`): by default the
paper's crossover and mutation of pairs of elites, as before the options existed (so every
earlier map-elites run is reproduced to the last digit); or mutation-only children, each of
one elite, with a per-gene mutation rate for labels and Gaussian or iso-line steps for real
genes (Vassiliades & Mouret 2018), which walk across the map (docs/evolution.md). An encoding
that brings its own operators (`mutate`, e.g. a CPPN's NEAT mutations) varies its genomes
itself. Parents are drawn uniformly from the archive's elites either way.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator
from pydantic_core import PydanticCustomError

from softevo.core.robots.genome import Genome
from softevo.core.search import operators
from softevo.core.search.archive import Elite
from softevo.core.search.paper_ga import room_for_children
from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.strategy import Generational
from softevo.core.search.variation import mate

if TYPE_CHECKING:
    from softevo.core.robots.encodings import Encoding
    from softevo.core.search.settings import SearchSettings

#: The options that only mutation-only variation reads.
_MUTATION_ONLY = ("label_rate", "real", "sigma", "line_sigma")


class MapElitesOptions(BaseModel):
    """How MAP-Elites makes children from its elites. The defaults are the paper's operators
    (the map-elites runs before these options, to the last digit); the `map-elites` preset sets
    the mutation-only variation measured best (EXPERIMENTS.md)."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)

    variation: Literal["crossover", "mutation"] = Field(
        "crossover",
        description="crossover: pairs of elites crossed and mutated as the GA does "
        "(crossover_probability, mutation_probability, mutation_genes, mutation_sigma); "
        "mutation: every child a mutant of one elite, no crossover (label_rate, real, sigma, "
        "line_sigma)",
    )
    label_rate: float | None = Field(
        None,
        ge=0,
        le=1,
        description="mutation: the chance that each discrete gene (a voxel's label) is "
        "redrawn to another value; null: mutation_genes genes a child (at least one)",
    )
    real: Literal["gaussian", "iso-line"] = Field(
        "gaussian",
        description="mutation: the step of real genes; gaussian: N(0, sigma x range) each; "
        "iso-line (Vassiliades & Mouret 2018): x + sigma N(0, I) x range + line_sigma "
        "N(0, 1) (y - x), y a second elite drawn uniformly",
    )
    sigma: float | None = Field(
        None, ge=0, le=10, description="mutation: the Gaussian step / range; null: mutation_sigma"
    )
    line_sigma: float = Field(
        0.2, ge=0, le=10, description="mutation, iso-line: the step along the line to y"
    )
    random: Literal["uniform", "spread"] = Field(
        "uniform",
        description="the random genomes of generation 0 and the immigrants; uniform: every "
        "label equally likely (the encoding's own); spread: each genome first draws its own "
        "label frequencies (a flat Dirichlet), so bodies of every size and mix are drawn",
    )

    @field_validator(*_MUTATION_ONLY)
    @classmethod
    def _applies(cls, value: Any, info: ValidationInfo) -> Any:
        """Settings of mutation-only variation are refused with crossover, not ignored."""
        if info.data.get("variation") != "mutation":
            raise PydanticCustomError("not_applicable", "applies to variation 'mutation' only")
        if info.field_name == "line_sigma" and info.data.get("real") != "iso-line":
            raise PydanticCustomError("not_applicable", "applies to real 'iso-line' only")
        return value


class MapElites(Generational):
    name = "map-elites"
    summary = (
        "quality-diversity: parents drawn from an archive that keeps the best robot of every "
        "cell of `descriptors` x `bins`, children by the GA's crossover and mutation or, "
        "with options variation 'mutation', mutants of one elite (per-gene label rate, "
        "Gaussian or iso-line real steps), plus immigrants"
    )
    Options = MapElitesOptions
    options: MapElitesOptions  # typed as its own, which __init__ validates
    uses = (
        "population",
        "generations",
        "descriptors",
        "bins",
        "crossover_probability",
        "mutation_probability",
        "mutation_genes",
        "mutation_sigma",
        "immigrants",
    )

    @classmethod
    def check(cls, config: SearchSettings) -> None:
        if not config.descriptors:
            raise ValueError("descriptors: map-elites needs at least one descriptor")
        room_for_children(config)

    def first(self, rng: np.random.Generator) -> list[Individual]:
        """The first individuals: `population` random genomes (`options.random`)."""
        return [Individual(self._random(rng), "random") for _ in range(self.config.population)]

    def _random(self, rng: np.random.Generator) -> Genome:
        """A random genome as `options.random` asks (an encoding with operators of its own
        draws its own)."""
        if self.options.random == "uniform" or hasattr(self.encoding, "mutate"):
            return self.encoding.random(rng)
        return spread_random(self.encoding, rng)

    def breed(self, state: StrategyState, rng: np.random.Generator) -> list[Individual]:
        """Children of elites drawn uniformly from the archive (`options.variation`), then
        immigrants. Children carry no parent indices (their parents are elites of any
        generation); their operator says `elite-...`."""
        config = self.config
        elites = state.archive.ordered() if state.archive else []
        if not elites:  # nothing survived to breed from: start again at random
            return self.first(rng)
        n_children = config.population - config.n_immigrants
        if self.options.variation == "mutation":
            children = [self._mutant(elites, rng) for _ in range(n_children)]
        else:
            children = self._crossed(elites, n_children, rng)
        return [
            *children[:n_children],
            *(Individual(self._random(rng), "immigrant") for _ in range(config.n_immigrants)),
        ]

    def _crossed(
        self, elites: list[Elite], n_children: int, rng: np.random.Generator
    ) -> list[Individual]:
        """Children of pairs of elites by the GA's crossover and mutation (`variation.mate`),
        drawn as before the options existed."""
        config, encoding = self.config, self.encoding
        mates = rng.integers(0, len(elites), size=2 * math.ceil(n_children / 2))
        children: list[Individual] = []
        for first, second in mates.reshape(-1, 2):
            pair = (
                Individual(elites[first].genome, "elite"),
                Individual(elites[second].genome, "elite"),
            )
            for child in mate(config, encoding, pair, (int(first), int(second)), rng):
                children.append(Individual(child.genome, f"elite-{child.operator}"))
        return children

    def _mutant(self, elites: list[Elite], rng: np.random.Generator) -> Individual:
        """A mutant of one elite drawn uniformly (and a second one drawn, the iso-line's y):
        labels by `label_rate` (or `mutation_genes` of them), real genes by a Gaussian or an
        iso-line step. An encoding with operators of its own (`mutate`) applies those."""
        config, encoding, options = self.config, self.encoding, self.options
        first, second = (int(i) for i in rng.integers(0, len(elites), size=2))
        parent = elites[first].genome
        if encoding.variation is not None:  # e.g. NEAT mutations of a CPPN
            return Individual(encoding.variation.mutate(config, parent, rng), "elite-copy+mutation")
        discrete = np.array(parent.discrete)
        if options.label_rate is None:
            genes = max(1, config.mutation_genes)
            discrete = operators.mutate_discrete(discrete, encoding.alphabet, genes, rng)
        else:
            discrete = operators.mutate_each(discrete, encoding.alphabet, options.label_rate, rng)
        sigma = config.mutation_sigma if options.sigma is None else options.sigma
        real, bounds = np.array(parent.real), encoding.real_bounds
        if options.real == "iso-line":
            other = np.array(elites[second].genome.real)
            real = operators.iso_line(real, other, bounds, sigma, options.line_sigma, rng)
            return Individual(encoding.genome(discrete, real), "elite-iso-line")
        real = operators.mutate_real(real, bounds, sigma, rng)
        return Individual(encoding.genome(discrete, real), "elite-mutation")


def spread_random(encoding: Encoding, rng: np.random.Generator) -> Genome:
    """A random genome whose labels follow frequencies of its own: each segment draws them
    from a flat Dirichlet, then its labels from them (so a body's filled and actuated fractions
    are spread over their ranges, where uniform labels give about 0.8 and 0.5); real genes
    uniform within their bounds, as `Encoding.random` draws them."""
    discrete = np.empty(encoding.n_discrete, dtype=np.int64)
    for segment in encoding.segments:
        weights = rng.dirichlet(np.ones(segment.alphabet))
        size = segment.stop - segment.start
        discrete[segment.start : segment.stop] = rng.choice(segment.alphabet, size, p=weights)
    low, high = encoding.real_bounds.T
    real = rng.uniform(low, high) if len(encoding.real_bounds) else np.empty(0)
    return encoding.genome(discrete, real)
