"""A write of many rows stores what the same rows written one at a time store, on SQLite and
on PostgreSQL (where two rows or more go as one statement that reads them from one JSON text):
JSON columns' text, strings that need escaping, NULLs, timestamps, and a repeated index (the
first one wins)."""

from __future__ import annotations

import json
import math
from datetime import UTC, datetime, timedelta
from typing import Any

from sqlalchemy import Text, cast, select

from softevo.api import store
from softevo.api.db import Database
from softevo.api.models import IndividualRow
from softevo.api.store.driving import _INSERT_MEMBER, MEMBER_COLUMNS
from softevo.api.store.fitness_rows import Landed
from tests.api.store.test_store import OWNER, driven, keep

AWKWARD = ["a,b", 'q"uote', "{brace}", "back\\slash", "NULL", "", "ünï ☃", "sp ace"]


def awkward_members() -> list[dict[str, Any]]:
    return [
        {
            "genome": {"discrete": [i, -i], "real": [0.1 * i, 1e-300], "tag": text},
            "genome_hash": f"h{i}{text}"[:32],
            "operator": text[:32],
            "parents": [i, i + 1],
        }
        for i, text in enumerate(AWKWARD)
    ]


def stored(db: Database, run_id: int) -> list[tuple[Any, ...]]:
    columns = IndividualRow.__table__.c
    with db.read_session() as session:
        rows = session.execute(
            select(
                columns["index"],
                cast(columns.genome, Text),
                columns.genome_hash,
                columns.operator,
                cast(columns.parents, Text),
                columns.status,
                columns.fitness,
                cast(columns.measures, Text),
                columns.eval_seconds,
                columns.worker,
            )
            .where(columns.run_id == run_id)
            .order_by(columns["index"])
        )
        return [tuple(row) for row in rows]


def test_many_rows_store_what_one_row_at_a_time_stores(db: Database) -> None:
    landed = [
        Landed(
            {0: 0.5, 1: math.nan, 2: -1e-12},
            'w,"1"',
            0.1,
            {0: {"heading": 12.5, "energy": math.nan}, 2: {"heading": math.nan}},
        ),
        Landed({3: 2.0, 0: 9.0}, None, None),  # index 0 again: the first fitness stays
        Landed({4: 1.0, 5: 0.0}, "w{}", 0.3, {4: {"heading": -180.0}}),
    ]
    one_by_one, at_once = driven(db), driven(db)
    with db.write_connection() as connection:  # the members one statement each
        for index, member in enumerate(awkward_members()):
            row = {"b_run": one_by_one, "b_generation": 0, "b_index": index}
            row |= {f"b_{column}": member[column] for column in MEMBER_COLUMNS}
            _INSERT_MEMBER.execute(connection, [row])
    keep(db, at_once, 0, awkward_members())
    for batch in landed:
        for index, value in batch.fitness.items():
            single = Landed({index: value}, batch.worker, batch.seconds_each, batch.measures)
            store.driving.save_fitness(db, one_by_one, OWNER, 0, [single])
    store.driving.save_fitness(db, at_once, OWNER, 0, landed)

    rows = stored(db, at_once)
    assert rows == stored(db, one_by_one)
    assert [json.loads(row[1])["tag"] for row in rows] == AWKWARD
    assert rows[0][5:7] == ("evaluated", 0.5) and rows[0][8:] == (0.1, 'w,"1"')
    assert json.loads(rows[0][7]) == {"heading": 12.5, "energy": None}  # NaN: null
    assert rows[1][5:8] == ("failed", None, "{}")  # no record: an empty one
    assert rows[6][5:] == ("pending", None, None, None, None)
    with db.read_session() as session:  # one timestamp for the call, read back as UTC
        times = set(
            session.scalars(
                select(IndividualRow.evaluated_at).where(
                    IndividualRow.run_id == at_once, IndividualRow.status != "pending"
                )
            )
        )
    (when,) = times
    assert when.utcoffset() == timedelta(0)
    assert abs(datetime.now(UTC) - when) < timedelta(minutes=1)


def test_a_seconds_figure_that_is_not_finite_is_stored_as_null(db: Database) -> None:
    """NaN is null in every column (`softevo.core.nulls`): a worker's odd timing neither fails
    the write (PostgreSQL's rows go as JSON, which has no NaN) nor is stored as a number."""
    run_id = driven(db)
    keep(db, run_id, 0, awkward_members())
    store.driving.save_fitness(db, run_id, OWNER, 0, [Landed({0: 0.5, 1: 0.25}, "w", math.nan)])
    rows = stored(db, run_id)
    assert [row[5:9] for row in rows[:2]] == [
        ("evaluated", 0.5, "{}", None),
        ("evaluated", 0.25, "{}", None),
    ]
