"""`nsga2`: NSGA-II (Deb et al. 2002), several objectives at once.

Every generation holds P = `population` individuals: the S = `survivors` x P best of the last
generation by NSGA-II's total order (`pareto.nsga2_order`: front rank, then crowding distance,
then the older individual, by (generation, index) of birth), and P - S children. Parents are
drawn by binary tournament among the survivors in that order and bred by the GA's own crossover
and mutation (`variation.mate`), for whatever encoding the run uses. Survivors are evaluated
again from the cache (counted `saved`), as the paper's GA's are, so lineage and the store keep
one row per member.

The objectives are the run's `objectives` (maximised vectors read from each individual's record
of measures); without them, the fitness alone. What `breed` needs is kept in `GAState.data` as
JSON: each member's objective values and birth key.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from pydantic import Field

from softevo.core.nulls import from_nulls, to_nulls
from softevo.core.search import pareto
from softevo.core.search.state import GAState, Individual
from softevo.core.search.strategy import Strategy
from softevo.core.search.variation import VariationOptions, explore_children, mate


class SurvivorOptions(VariationOptions):
    """The share of a generation that survives into the next, and how children are made."""

    survivors: float = Field(
        0.5,
        gt=0,
        lt=1,
        description="fraction of each generation kept (by the algorithm's selection) into the "
        "next; the rest of the next are new",
    )


def n_survivors(population: int, fraction: float, newcomers: int = 0) -> int:
    """Survivors of a generation of `population`: round(fraction x P), at least 1, leaving room
    for at least one child beside `newcomers`."""
    return max(1, min(population - 1 - newcomers, math.floor(fraction * population + 0.5)))


def born_keys(state: GAState, individuals: list[Individual]) -> list[list[int]]:
    """Each member's birth (generation, index): a survivor keeps its own, anyone else is born
    now. The tie-break key of both strategies: unique, and never the order results arrived in."""
    before = (state.data or {}).get("born", [])
    return [
        list(before[item.parents[0]]) if item.operator == "survivor" else [state.generation, i]
        for i, item in enumerate(individuals)
    ]


def told_values(state: GAState) -> tuple[np.ndarray, np.ndarray]:
    """The last generation's objective values ([N, M], NaN = failed) and birth keys ([N, 2])
    as `tell` kept them; ValueError naming what is missing otherwise."""
    data = state.data or {}
    if "values" not in data or "born" not in data:
        raise ValueError("state data: values and born are missing (not a state this wrote)")
    values = np.array([from_nulls(row) for row in data["values"]], dtype=np.float64)
    born = np.array(data["born"], dtype=np.int64).reshape(-1, 2)
    if len(values) != len(born) or len(born) != len(state.previous or []):
        raise ValueError(
            f"state data: {len(values)} values and {len(born)} births for "
            f"{len(state.previous or [])} individuals"
        )
    return values, born


class NSGA2(Strategy):
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
        self, state: GAState, individuals: list[Individual], values: np.ndarray
    ) -> dict[str, Any]:
        """What `breed` reads of a told generation (JSON)."""
        return {
            "values": [to_nulls(row) for row in values.tolist()],
            "born": born_keys(state, individuals),
        }

    def breed(self, state: GAState, rng: np.random.Generator) -> list[Individual]:
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
