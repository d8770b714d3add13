"""A run's Pareto front: the non-dominated set of every individual it evaluated (its figure is
`softevo.core.outputs.front_figure`'s).

Individuals come as plain rows (`generation`, `index`, `fitness`, `operator`, `measures`), as
population.csv, the store and `GET /runs/{id}/individuals` give them. A `survivor` row is the
same genome again (its record comes from the cache), so it is counted once, where it first
appeared. A failed row (no fitness, or an objective not measured) is on no front.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any, TypeVar

import numpy as np

from softevo.core.search import pareto
from softevo.core.search.vectors import ObjectiveSpec, objective_values

Row = Mapping[str, Any]
#: a row of the caller's own type (a dict, a mapping), given back as it came
R = TypeVar("R", bound=Row)


def front_values(specs: Sequence[ObjectiveSpec], rows: Sequence[Row]) -> np.ndarray:
    """[N, M] maximised objective values of the rows (NaN: failed, or a survivor's repeat)."""
    fitness = np.array(
        [np.nan if row["fitness"] is None else row["fitness"] for row in rows], dtype=np.float64
    )
    fitness[[row.get("operator") == "survivor" for row in rows]] = np.nan
    records = [row.get("measures") or {} for row in rows]
    return objective_values(specs, records, fitness).reshape(len(rows), max(1, len(specs)))


def front_rows(specs: Sequence[ObjectiveSpec], rows: Iterable[R], chunk: int = 4096) -> list[R]:
    """The rows on the front, in their order: no other row dominates them. Rows are read
    `chunk` at a time and only the front so far is kept, so memory follows the front, not the
    run. A row whose `genome_hash` is already on the front is the same robot again and left
    out (a copy whose first appearance was dominated is dominated too)."""
    front: list[R] = []
    on_front: set[str] = set()
    batch: list[R] = []
    for row in rows:
        genome_hash = row.get("genome_hash")
        if genome_hash is not None:
            if genome_hash in on_front:
                continue
            on_front.add(genome_hash)  # on the front, or in the batch about to meet it
        batch.append(row)
        if len(batch) >= chunk:
            front = _merged(specs, front, batch)
            on_front = {r["genome_hash"] for r in front if r.get("genome_hash") is not None}
            batch = []
    if batch:
        front = _merged(specs, front, batch)
    return front


def _merged(specs: Sequence[ObjectiveSpec], front: list[R], batch: list[R]) -> list[R]:
    """The non-dominated rows of the front so far and the next batch, in order."""
    candidates = [*front, *batch]
    mask = pareto.nondominated_mask(front_values(specs, candidates))
    return [row for row, kept in zip(candidates, mask, strict=True) if kept]
