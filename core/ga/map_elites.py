"""`map-elites`: quality-diversity. Parents are drawn from an archive that keeps the fittest
robot of every cell of `descriptors` x `bins` (`softevo.core.ga.archive`), so the run keeps the
best of every kind of body instead of one kind."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from softevo.core.ga.paper_ga import room_for_children
from softevo.core.ga.state import GAState, Individual
from softevo.core.ga.strategy import Strategy
from softevo.core.ga.variation import mate

if TYPE_CHECKING:
    from softevo.core.ga.algorithm import GAConfig


class MapElites(Strategy):
    name = "map-elites"
    summary = (
        "quality-diversity: parents drawn from an archive that keeps the best robot of every "
        "cell of `descriptors` x `bins`, children by the GA's crossover and mutation, plus "
        "immigrants"
    )
    uses = (
        "population", "generations", "descriptors", "bins", "crossover_probability",
        "mutation_probability", "mutation_genes", "mutation_sigma", "immigrants",
    )  # fmt: skip

    @classmethod
    def check(cls, config: GAConfig) -> None:
        if not config.descriptors:
            raise ValueError("descriptors: map-elites needs at least one descriptor")
        room_for_children(config)

    def breed(self, state: GAState, rng: np.random.Generator) -> list[Individual]:
        """Children of pairs of elites drawn uniformly from the archive, by the GA's crossover
        and mutation, then immigrants. Children carry no parent indices (their parents are
        elites of any generation); their operator says `elite-...`."""
        config, encoding = self.config, self.encoding
        elites = state.archive.ordered() if state.archive else []
        if not elites:  # nothing survived to breed from: start again at random
            return self.first(rng)
        n_children = config.population - config.n_immigrants
        mates = rng.integers(0, len(elites), size=2 * math.ceil(n_children / 2))
        children: list[Individual] = []
        for first, second in mates.reshape(-1, 2):
            pair = (
                Individual(elites[first].genome, "elite"),
                Individual(elites[second].genome, "elite"),
            )
            for child in mate(config, encoding, pair, (int(first), int(second)), rng):
                children.append(Individual(child.genome, f"elite-{child.operator}"))
        return [
            *children[:n_children],
            *(Individual(encoding.random(rng), "immigrant") for _ in range(config.n_immigrants)),
        ]
