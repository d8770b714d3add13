"""`nsga2`: NSGA-II (Deb et al. 2002), several objectives at once.

Every generation holds P = `population` individuals: the S = `survivors` x P best of the last
generation by NSGA-II's total order (`pareto.nsga2_order`: front rank, then crowding distance,
then the older individual, by (generation, index) of birth), and P - S children. Parents are
drawn by binary tournament among the survivors in that order and bred by the GA's own crossover
and mutation (`variation.mate`), for whatever encoding the run uses. Survivors are evaluated
again from the cache (counted `saved`), as the paper's GA's are, so lineage and the store keep
one row per member.

The objectives are the run's `objectives` (maximised vectors read from each individual's record
of measures); without them, the fitness alone. What `breed` needs is kept in `StrategyState.data` as
JSON: each member's objective values and birth key.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from softevo.core.search import pareto
from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.strategy import Generational
from softevo.core.search.survivors import SurvivorOptions, n_survivors, told_record, told_values
from softevo.core.search.variation import explore_children, mate


class NSGA2(Generational):
    name = "nsga2"
    summary = (
        "NSGA-II: survivors by non-dominated rank and crowding distance over `objectives` (or "
        "the fitness), parents by binary tournament, the GA's crossover and mutation"
    )
    uses: ClassVar[tuple[str, ...]] = (
        "population",
        "generations",
        "objectives",
        "crossover_probability",
        "mutation_probability",
        "mutation_genes",
        "mutation_sigma",
    )
    Options = SurvivorOptions
    options: SurvivorOptions  # typed as its own, which __init__ validates
    reads_objectives = True

    def kept(
        self, state: StrategyState, individuals: list[Individual], values: np.ndarray
    ) -> dict[str, Any]:
        """What `breed` reads of a told generation (JSON)."""
        return told_record(state, individuals, values)

    def breed(self, state: StrategyState, rng: np.random.Generator) -> list[Individual]:
        config, encoding = self.config, self.encoding
        parents = state.previous or []
        values, born = told_values(state)
        survivors = pareto.nsga2_order(values, born)[
            : n_survivors(config.population, self.options.survivors)
        ]
        n_children = config.population - len(survivors)
        # the survivors are in order, best first: a tournament among their positions
        drawn = pareto.binary_tournament(
            rng, np.arange(len(survivors)), 2 * math.ceil(n_children / 2)
        )
        mates = survivors[drawn]
        if self.options.variation == "explore":
            mutated = self.options.mutated_genes
            children = explore_children(config, encoding, parents, mates, n_children, mutated, rng)
        else:
            children = []
            for first, second in mates.reshape(-1, 2):
                pair = (parents[first], parents[second])
                children.extend(mate(config, encoding, pair, (int(first), int(second)), rng))
        return [
            *(Individual(parents[i].genome, "survivor", (int(i),)) for i in survivors),
            *children[:n_children],
        ]
