"""`afpo`: age-fitness Pareto optimisation (Schmidt & Lipson 2010), as evosoro runs it.

Every individual has a genotypic age: the generations since its lineage began with a random
genome (a child inherits its parent's lineage, so its age; a newcomer's age is 0). Each
generation of P = `population` keeps the S = `survivors` x P best of the last generation by
Pareto selection on (age, each objective), younger being better (`pareto.afpo_select`: whole
Pareto layers while they fit, the last one filled by the first objective, then the others, then
the younger, then the older birth (generation, index)); then P - S - 1 children, each a mutant
of a survivor taken in selection order (the GA's mutation: `mutation_genes`, `mutation_sigma`),
and one random newcomer. Age protection lets a new lineage improve before it must compete with
old, fit ones, which is what keeps diversity in.

The objectives are the run's `objectives`, or the fitness alone; works with one or several.
`StrategyState.data` keeps, as JSON, each member's objective values, birth and lineage start.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from softevo.core.search import pareto
from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.strategy import Generational
from softevo.core.search.survivors import SurvivorOptions, n_survivors, told_record, told_values
from softevo.core.search.variation import explore_mutants, mutant

if TYPE_CHECKING:
    from softevo.core.search.settings import SearchSettings


class AFPO(Generational):
    name = "afpo"
    summary = (
        "age-fitness Pareto optimisation: survivors by Pareto selection on (genotypic age, "
        "`objectives` or the fitness), mutants of them and one random newcomer a generation"
    )
    uses = ("population", "generations", "objectives", "mutation_genes", "mutation_sigma")
    Options = SurvivorOptions
    options: SurvivorOptions  # typed as its own, which __init__ validates
    reads_objectives = True

    @classmethod
    def check(cls, config: SearchSettings) -> None:
        if config.population < 3:
            raise ValueError(
                f"population: afpo needs at least 3 (survivors, a child and a newcomer), "
                f"got {config.population}"
            )

    def kept(
        self, state: StrategyState, individuals: list[Individual], values: np.ndarray
    ) -> dict[str, Any]:
        """NSGA-II's record and each member's lineage start (`founded`, a generation)."""
        before = (state.data or {}).get("founded", [])
        founded = [
            before[item.parents[0]] if item.parents and before else state.generation
            for item in individuals
        ]
        return {**told_record(state, individuals, values), "founded": founded}

    def breed(self, state: StrategyState, rng: np.random.Generator) -> list[Individual]:
        config, encoding = self.config, self.encoding
        parents = state.previous or []
        values, born = told_values(state)
        founded = np.asarray((state.data or {}).get("founded", []), dtype=np.float64)
        if founded.shape != (len(parents),):
            raise ValueError(f"state data: founded must hold {len(parents)} generations")
        ages = state.generation - founded
        count = n_survivors(config.population, self.options.survivors, newcomers=1)
        survivors = pareto.afpo_select(ages, values, count, born)
        chosen = [int(survivors[k % count]) for k in range(config.population - count - 1)]
        if self.options.variation == "explore":
            mutated = self.options.mutated_genes
            children = explore_mutants(config, encoding, parents, chosen, mutated, rng)
        else:
            children = [mutant(config, encoding, parents[i], i, rng) for i in chosen]
        return [
            *(Individual(parents[i].genome, "survivor", (int(i),)) for i in survivors),
            *children,
            Individual(encoding.random(rng), "immigrant"),
        ]
