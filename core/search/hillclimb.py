"""`hillclimb`: a (1 + lambda) hill climber, the simplest baseline that uses variation."""

from __future__ import annotations

import numpy as np

from softevo.core.search import operators
from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.strategy import Generational
from softevo.core.search.variation import mutant


class HillClimb(Generational):
    name = "hillclimb"
    summary = (
        "a (1+lambda) hill climber: the best of the last generation and population-1 mutants of it"
    )
    uses = ("population", "generations", "mutation_genes", "mutation_sigma")

    def breed(self, state: StrategyState, rng: np.random.Generator) -> list[Individual]:
        """The best of the last generation (so the best so far) and P-1 mutants of it, every
        one mutated with the GA's mutation (`mutation_genes`, `mutation_sigma`)."""
        parents = state.previous or []
        best = int(operators.rank_order(np.asarray(state.previous_fitness))[0])
        parent = parents[best]
        climbers = [Individual(parent.genome, "survivor", (best,))]
        for _ in range(self.config.population - 1):
            climbers.append(mutant(self.config, self.encoding, parent, best, rng))
        return climbers
