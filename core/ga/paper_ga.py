"""`ga`: the paper's genetic algorithm, and the classic selections beside it.

One generation (g > 0), with P the population size:

1. Survivors: `grouped` selection keeps the best `survival` fraction of each of `groups` random
   groups (the paper); `tournament` and `roulette` keep only the best individual, if `elitism`.
2. Immigrants: round(`immigrants` * P) new random genomes.
3. Children fill the rest, in pairs: two parents (uniform among the survivors for `grouped`, by
   tournament or roulette wheel otherwise), crossed and mutated (`softevo.core.ga.variation`).
4. With `elitism`, the best individual of g-1 is always among the survivors, so best-so-far never
   falls. (Grouped truncation keeps each group's best, hence always the overall best.)
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from softevo.core.ga import operators
from softevo.core.ga.state import GAState, Individual
from softevo.core.ga.strategy import Strategy
from softevo.core.ga.variation import mate

if TYPE_CHECKING:
    from softevo.core.ga.algorithm import GAConfig


class PaperGA(Strategy):
    name = "ga"
    summary = (
        "the paper's genetic algorithm: survivors by grouped truncation (or tournament / "
        "roulette with elitism), two-point crossover, mutation, random immigrants"
    )
    uses = (
        "population", "generations", "selection", "groups", "survival", "tournament_size",
        "crossover_probability", "mutation_probability", "mutation_genes", "mutation_sigma",
        "immigrants", "elitism",
    )  # fmt: skip

    @classmethod
    def check(cls, config: GAConfig) -> None:
        room_for_children(config)

    def breed(self, state: GAState, rng: np.random.Generator) -> list[Individual]:
        config, encoding = self.config, self.encoding
        parents = state.previous or []
        fitness = np.asarray(state.previous_fitness, dtype=np.float64)
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
            pair = (parents[first], parents[second])
            children.extend(mate(config, encoding, pair, (first, second), rng))
        return [
            *(Individual(parents[i].genome, "survivor", (int(i),)) for i in survivors),
            *children[:n_children],
            *(Individual(encoding.random(rng), "immigrant") for _ in range(config.n_immigrants)),
        ]


def room_for_children(config: GAConfig) -> None:
    """Immigrants must leave room for survivors and children."""
    if config.n_immigrants >= config.population:
        raise ValueError(
            f"immigrants: {config.immigrants} of {config.population} leaves no room for "
            "survivors and children"
        )
