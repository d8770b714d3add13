"""Individuals' fitness as the driver writes it: batches that landed (`Landed`), their rows for
one UPDATE (one statement for any number of batches; a recordset on PostgreSQL), and each
record of measures as `individuals.measures` stores it."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from sqlalchemy import Connection, bindparam, update

from softevo.api.db import EncodedJSON
from softevo.api.models import INDIVIDUALS, PENDING
from softevo.api.store.runs import now
from softevo.api.store.statements import DriverStatement
from softevo.core.nulls import Record, record_text, to_null
from softevo.core.status import IndividualStatus

_SET_FITNESS = DriverStatement(
    update(INDIVIDUALS)
    .where(
        INDIVIDUALS.c.run_id == bindparam("b_run"),
        INDIVIDUALS.c.generation == bindparam("b_generation"),
        INDIVIDUALS.c["index"] == bindparam("b_index"),
        INDIVIDUALS.c.status == PENDING,  # never a second fitness
    )
    .values(
        fitness=bindparam("b_fitness"),
        measures=bindparam("b_measures"),
        status=bindparam("b_status"),
        eval_seconds=bindparam("b_seconds"),
        worker=bindparam("b_worker"),
        evaluated_at=bindparam("b_at"),
    ),
    postgres_rows=f"""
    UPDATE individuals SET fitness = v.b_fitness, measures = v.b_measures::json,
        status = v.b_status, eval_seconds = v.b_seconds, worker = v.b_worker,
        evaluated_at = v.b_at
    FROM json_to_recordset(%(b_rows)s::json) AS v(b_index integer, b_fitness float8,
        b_measures text, b_status text, b_seconds float8, b_worker text, b_at timestamptz)
    WHERE individuals.run_id = %(b_run)s AND individuals.generation = %(b_generation)s
        AND individuals."index" = v.b_index AND individuals.status = '{PENDING}'""",
    scalars=("b_run", "b_generation"),
)


@dataclass(frozen=True)
class Landed:
    """One batch's fitness (by index in its generation; NaN = failed), the worker that
    evaluated it, the seconds each of its robots took (None for fitness from the cache) and
    their records of measures (by index; NaN: stored as null; missing: an empty record)."""

    fitness: dict[int, float]
    worker: str | None
    seconds_each: float | None
    measures: Mapping[int, Mapping[str, float]] = field(default_factory=dict)
    generation: int | None = None  # its generation, when not the one it is written with


def fitness_rows(
    run_id: int, generation: int, landed: Sequence[Landed], status: IndividualStatus | None = None
) -> list[dict[str, Any]]:
    """Rows for `_SET_FITNESS`: evaluated or failed by the value, unless `status` is given."""
    at = now()
    return [
        {
            "b_run": run_id,
            "b_index": index,
            "b_generation": generation if batch.generation is None else batch.generation,
            "b_fitness": to_null(value),
            "b_seconds": to_null(batch.seconds_each),
            "b_measures": measures_text(batch.measures.get(index)),
            "b_worker": None if batch.worker is None else batch.worker[:128],
            "b_at": at,
            "b_status": (
                status
                or (
                    IndividualStatus.EVALUATED
                    if to_null(value) is not None
                    else IndividualStatus.FAILED
                )
            ).value,
        }
        for batch in landed
        for index, value in batch.fitness.items()
    ]


def measures_text(record: Mapping[str, float] | None) -> EncodedJSON:
    """A record of measures as `individuals.measures` stores it (`record_text`: a compact JSON
    object, NaN as null): a `Record`'s text as the job sent it, else encoded here once (the
    record keeps it for the generations its genome is a member of again)."""
    if not record:
        return EncodedJSON("{}")
    text = getattr(record, "text", None)  # as the job sent it, or as written before
    if text is None:
        text = record_text(record)
        if isinstance(record, Record):
            record.text = text
    return EncodedJSON(text)


def set_fitness(connection: Connection, rows: list[dict[str, Any]]) -> None:
    """`_SET_FITNESS` for rows, the first of each index only: a later one for the same index
    would find it no longer pending, as it does in a later call. One statement a generation."""
    first: dict[int, dict[int, dict[str, Any]]] = {}
    for row in rows:
        first.setdefault(row["b_generation"], {}).setdefault(row["b_index"], row)
    for by_index in first.values():
        _SET_FITNESS.execute(connection, list(by_index.values()))
