"""A run's Pareto front: the non-dominated set of every individual it evaluated (its figure is
`softevo.core.front_figure`'s).

Individuals come as plain rows (`generation`, `index`, `fitness`, `operator`, `measures`), as
population.csv, the store and `GET /runs/{id}/individuals` give them. A `survivor` row is the
same genome again (its record comes from the cache), so it is counted once, where it first
appeared. A failed row (no fitness, or an objective not measured) is on no front.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from softevo.core.ga import pareto
from softevo.core.ga.vectors import ObjectiveSpec, objective_values

Row = Mapping[str, Any]


def front_values(specs: Sequence[ObjectiveSpec], rows: Sequence[Row]) -> np.ndarray:
    """[N, M] maximised objective values of the rows (NaN: failed, or a survivor's repeat)."""
    fitness = np.array(
        [np.nan if row["fitness"] is None else row["fitness"] for row in rows], dtype=np.float64
    )
    fitness[[row.get("operator") == "survivor" for row in rows]] = np.nan
    records = [row.get("measures") or {} for row in rows]
    return objective_values(specs, records, fitness).reshape(len(rows), max(1, len(specs)))


def front_rows(specs: Sequence[ObjectiveSpec], rows: Sequence[Row]) -> list[Row]:
    """The rows on the front, in their order: no other row dominates them."""
    if not rows:
        return []
    mask = pareto.nondominated_mask(front_values(specs, rows))
    return [row for row, kept in zip(rows, mask, strict=True) if kept]
