"""`random`: random search, the baseline every algorithm must beat on the same budget."""

from __future__ import annotations

import numpy as np

from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.strategy import Generational


class RandomSearch(Generational):
    name = "random"
    summary = "random search: `population` new random genomes every generation"

    def breed(self, state: StrategyState, rng: np.random.Generator) -> list[Individual]:
        return self.first(rng)
