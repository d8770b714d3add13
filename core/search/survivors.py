"""What NSGA-II and AFPO share, as functions rather than a base class: the share of a
generation that survives, each member's birth key (the tie-break that never depends on when a
result arrived), and the record of a told generation (`StrategyState.data` JSON) both breed from.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydantic import Field

from softevo.core.nulls import from_nulls, to_nulls
from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.variation import VariationOptions


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


def born_keys(state: StrategyState, individuals: list[Individual]) -> list[list[int]]:
    """Each member's birth (generation, index): a survivor keeps its own, anyone else is born
    now. The tie-break key of both strategies: unique, and never the order results arrived in."""
    before = (state.data or {}).get("born", [])
    return [
        list(before[item.parents[0]]) if item.operator == "survivor" else [state.generation, i]
        for i, item in enumerate(individuals)
    ]


def told_values(state: StrategyState) -> tuple[np.ndarray, np.ndarray]:
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


def told_record(
    state: StrategyState, individuals: list[Individual], values: np.ndarray
) -> dict[str, Any]:
    """What a survivor strategy's `breed` reads of a told generation (JSON): each member's
    maximised objective values and birth key."""
    return {
        "values": [to_nulls(row) for row in values.tolist()],
        "born": born_keys(state, individuals),
    }
