"""Every evaluated individual's record of measures (`SimResult.measures`: name -> number or null),
a JSON object in `individuals.measures`, in place of the one `heading` column of revision 0003:
objectives and behavioural descriptors read their measure by name, and a new measure needs no
migration.

Upgrading keeps every stored value to the bit: each row that is not pending gets the record of
what was stored, its fitness under its objective's measure (the run's `objective`: speed,
forward_speed, climb_rate or efficiency) and its heading (a NULL, a failed robot's, left out: not
measured). Other measures were never stored and stay unknown; a run taken over goes on with the
same fitness and the same `heading` descriptor values, so with the same curve and archive.

The `heading` column is dropped, not kept beside the record: two copies of one number would have
to be written alike by every write and could disagree; `measures` holds it. The cost is that an
API process of the previous release cannot write this schema, so stop those before upgrading
(`softevo serve` already refuses a database behind its release). Downgrading restores the column
from each record's `heading` and drops the records (the other measures are lost).

Revision ID: 0004
Revises: 0003
Create Date: 2026-12-05
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0004"
down_revision = "0003"
branch_labels = None
depends_on = None

#: objective -> the measure that is its fitness (`softevo.core.objectives.OBJECTIVE_MEASURES` as
#: it was at this revision, spelled out so this revision keeps its meaning)
OBJECTIVE_MEASURES = {
    "speed": "speed",
    "forward": "forward_speed",
    "climb": "climb_rate",
    "efficiency": "efficiency",
}
#: rows updated per statement
CHUNK = 5000

runs = sa.table("runs", sa.column("id", sa.Integer), sa.column("config", sa.JSON))


def _individuals(*columns: str) -> sa.TableClause:
    types = {
        "id": sa.Integer,
        "run_id": sa.Integer,
        "status": sa.String,
        "fitness": sa.Float,
        "heading": sa.Float,
        "measures": sa.JSON,
    }
    return sa.table("individuals", *(sa.column(name, types[name]) for name in columns))


def _record(measure: str, fitness: float | None, heading: float | None) -> dict[str, float]:
    """What a row kept, as a record: NULLs (a failed robot's) left out, not measured."""
    record = {measure: fitness, "heading": heading}
    return {name: value for name, value in record.items() if value is not None}


def upgrade() -> None:
    with op.batch_alter_table("individuals") as table:
        table.add_column(sa.Column("measures", sa.JSON, nullable=True))
    bind = op.get_bind()
    measure = {
        run_id: OBJECTIVE_MEASURES.get((config or {}).get("objective") or "speed", "speed")
        for run_id, config in bind.execute(sa.select(runs.c.id, runs.c.config))
    }
    old = _individuals("id", "run_id", "status", "fitness", "heading")
    new = _individuals("id", "measures")
    found = bind.execute(
        sa.select(old.c.id, old.c.run_id, old.c.fitness, old.c.heading).where(
            old.c.status != "pending"
        )
    ).all()
    statement = (
        sa.update(new)
        .where(new.c.id == sa.bindparam("b_id"))
        .values(measures=sa.bindparam("b_measures", type_=sa.JSON))
    )
    for start in range(0, len(found), CHUNK):
        rows = [
            {"b_id": row.id, "b_measures": _record(measure[row.run_id], row.fitness, row.heading)}
            for row in found[start : start + CHUNK]
        ]
        bind.execute(statement, rows)
    with op.batch_alter_table("individuals") as table:
        table.drop_column("heading")


def downgrade() -> None:
    with op.batch_alter_table("individuals") as table:
        table.add_column(sa.Column("heading", sa.Float, nullable=True))
    bind = op.get_bind()
    stored = _individuals("id", "measures")
    found = bind.execute(
        sa.select(stored.c.id, stored.c.measures).where(stored.c.measures.is_not(None))
    ).all()
    target = _individuals("id", "heading")
    statement = (
        sa.update(target)
        .where(target.c.id == sa.bindparam("b_id"))
        .values(heading=sa.bindparam("b_heading"))
    )
    rows = [
        {"b_id": row.id, "b_heading": (row.measures or {}).get("heading")}
        for row in found
        if (row.measures or {}).get("heading") is not None
    ]
    for start in range(0, len(rows), CHUNK):
        bind.execute(statement, rows[start : start + CHUNK])
    with op.batch_alter_table("individuals") as table:
        table.drop_column("measures")
