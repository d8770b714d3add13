"""A run's births as a driver finds them when it takes the run over: the members asked (and
perhaps evaluated) in the rows after the last committed one, read once."""

from __future__ import annotations

from sqlalchemy import select

from softevo.api.db import Database
from softevo.api.models import INDIVIDUALS, PENDING
from softevo.core.nulls import from_null, from_null_record


def stored_births(
    db: Database, run_id: int, since: int
) -> dict[tuple[int, int], tuple[str, float | None, dict[str, float]]]:
    """The members stored in generations `since` and later, by (generation, index): genome
    hash, fitness (None: not evaluated yet; NaN: failed) and record of measures. The births in
    flight, read once when a driver takes the run over."""
    columns = INDIVIDUALS.c
    with db.read_session() as session:
        rows = session.execute(
            select(
                columns.generation,
                columns["index"],
                columns.genome_hash,
                columns.status,
                columns.fitness,
                columns.measures,
            ).where(columns.run_id == run_id, columns.generation >= since)
        ).all()
    return {
        (generation, index): (
            genome_hash,
            None if status == PENDING else from_null(fitness),
            {} if status == PENDING else from_null_record(measures),
        )
        for generation, index, genome_hash, status, fitness, measures in rows
    }
