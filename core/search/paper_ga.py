"""`ga`: the paper's genetic algorithm, and the classic selections beside it.

One generation (g > 0), with P the population size:

1. Survivors: `grouped` selection keeps the best `survival` fraction of each of `groups` random
   groups (the paper); `tournament` and `roulette` keep only the best individual, if `elitism`.
2. Immigrants: round(`immigrants` * P) new random genomes.
3. Children fill the rest, in pairs: two parents (uniform among the survivors for `grouped`, by
   tournament or roulette wheel otherwise), crossed and mutated (`softevo.core.search.variation`).
4. With `elitism`, the best individual of g-1 is always among the survivors, so best-so-far never
   falls. (Grouped truncation keeps each group's best, hence always the overall best.)

Option `weights` (a weighted-sum GA, the classic way to trade objectives off with one fitness):
steps 1-4 rank on the weighted sum w . v of the run's `objectives` (v: each measure maximised, a
minimised one negated; NaN if any is missing) instead of the fitness. The fitness, best so far
and the curve stay `objective`'s, and the front is kept beside it as for any algorithm, so a
weighted GA and NSGA-II are compared on the same front. The sums of the last generation are kept
in `StrategyState.data` (`weighted`), so a resumed run selects as the undisturbed one.

Option `variation` "explore" (issue 51, `softevo.core.search.variation`): step 3's children are
mutated gene by gene and a repeat of a genome already met is re-drawn; immigrants stay random.
The default is the paper's operators, for new runs too: every ga preset is the paper's.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from pydantic import Field, field_validator

from softevo.core.nulls import from_nulls, to_nulls
from softevo.core.robots.encodings import Encoding
from softevo.core.search import operators
from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.strategy import Generational
from softevo.core.search.variation import VariationOptions, explore_children, mate

if TYPE_CHECKING:
    from softevo.core.search.settings import SearchSettings


#: The key of `StrategyState.data` under which a weighted GA keeps the last generation's sums.
WEIGHTED_KEY = "weighted"


class GAOptions(VariationOptions):
    """The GA's own settings: an optional weighted sum of the objectives to select on, and how
    children are made (the paper's operators unless `variation` is explore)."""

    weights: list[float] | None = Field(
        None,
        description="select on the weighted sum of the run's `objectives` instead of the "
        "fitness: one weight >= 0 per objective, applied to its maximised value (a minimised "
        "measure negated), in the measures' own units; the fitness and curve stay `objective`'s",
    )

    @field_validator("weights")
    @classmethod
    def _weights(cls, value: list[float] | None) -> list[float] | None:
        if value is not None and (any(w < 0 for w in value) or not any(w > 0 for w in value)):
            raise ValueError(f"each weight >= 0 and one > 0, got {value}")
        return value


class PaperGA(Generational):
    name = "ga"
    summary = (
        "the paper's genetic algorithm: survivors by grouped truncation (or tournament / "
        "roulette with elitism), two-point crossover, mutation, random immigrants"
    )
    uses = (
        "population",
        "generations",
        "selection",
        "groups",
        "survival",
        "tournament_size",
        "crossover_probability",
        "mutation_probability",
        "mutation_genes",
        "mutation_sigma",
        "immigrants",
        "elitism",
    )
    Options = GAOptions
    options: GAOptions  # typed as its own, which __init__ validates

    def __init__(self, config: SearchSettings, encoding: Encoding) -> None:
        super().__init__(config, encoding)
        self.weights = None if self.options.weights is None else np.array(self.options.weights)
        self.reads_objectives = self.weights is not None  # `kept` then gets the sums' inputs

    @classmethod
    def check(cls, config: SearchSettings) -> None:
        room_for_children(config)
        weights = config.options.get("weights")
        if isinstance(weights, list) and len(weights) != len(config.objectives):
            raise ValueError(
                f"options.weights: one weight per objective, got {len(weights)} for "
                f"{len(config.objectives)} objectives (set `objectives`)"
            )

    @classmethod
    def breeds_on(cls, config: SearchSettings, setting: str) -> bool:
        """A weighted GA selects on the objectives."""
        weighted = setting == "objectives" and config.options.get("weights") is not None
        return weighted or super().breeds_on(config, setting)

    def kept(
        self, state: StrategyState, individuals: list[Individual], values: np.ndarray
    ) -> dict[str, list[float | None]]:
        """A weighted GA's sums of the told generation (NaN where an objective failed)."""
        return {WEIGHTED_KEY: to_nulls((values @ self.weights).tolist())}

    def selected_on(self, state: StrategyState) -> np.ndarray:
        """What selection ranks the last generation by: the fitness, or the weighted sums."""
        if self.weights is None:
            return np.asarray(state.previous_fitness, dtype=np.float64)
        sums = (state.data or {}).get(WEIGHTED_KEY)
        if sums is None or len(sums) != len(state.previous or []):
            raise ValueError(f"state data: {WEIGHTED_KEY} must hold one sum per individual")
        return from_nulls(sums)

    def breed(self, state: StrategyState, rng: np.random.Generator) -> list[Individual]:
        config, encoding = self.config, self.encoding
        parents = state.previous or []
        fitness = self.selected_on(state)
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
        children = self.children(parents, mates, n_children, rng)
        return [
            *(Individual(parents[i].genome, "survivor", (int(i),)) for i in survivors),
            *children,
            *(Individual(encoding.random(rng), "immigrant") for _ in range(config.n_immigrants)),
        ]

    def children(
        self,
        parents: list[Individual],
        mates: np.ndarray,
        count: int,
        rng: np.random.Generator,
    ) -> list[Individual]:
        """`count` children of the pairs `mates`, by the paper's operators or exploring ones."""
        config, encoding = self.config, self.encoding
        if self.options.variation == "explore":
            mutated = self.options.mutated_genes
            return explore_children(config, encoding, parents, mates, count, mutated, rng)
        children: list[Individual] = []
        for first, second in mates.reshape(-1, 2):
            pair = (parents[first], parents[second])
            children.extend(mate(config, encoding, pair, (first, second), rng))
        return children[:count]


def room_for_children(config: SearchSettings) -> None:
    """Immigrants must leave room for survivors and children."""
    if config.n_immigrants >= config.population:
        raise ValueError(
            f"immigrants: {config.immigrants} of {config.population} leaves no room for "
            "survivors and children"
        )
