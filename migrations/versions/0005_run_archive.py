"""A quality-diversity run's archive in a column of its own (`runs.archive`), no longer inside the
GA state: `GET /runs/{id}/archive` reads the archive alone, never the GA state (two populations
of JSON, tens of MB for a large run), as every other read route already does not.

Upgrading copies each stored archive out of its run's GA state into the column, one run at a
time; the state keeps its copy until the run's next commit writes the state without it (the
coordinator reads the column over it). Downgrading puts each archive back into its GA state and
drops the column.

Revision ID: 0005
Revises: 0004
Create Date: 2026-12-05
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0005"
down_revision = "0004"
branch_labels = None
depends_on = None

runs = sa.table(
    "runs",
    sa.column("id", sa.Integer),
    sa.column("ga_state", sa.JSON),
    sa.column("archive", sa.JSON),
)


def upgrade() -> None:
    # plain ALTER TABLE, never batch mode's copy of `runs` on SQLite: dropping the old table
    # would delete every run's generations and individuals (ON DELETE CASCADE)
    op.add_column("runs", sa.Column("archive", sa.JSON, nullable=True))
    bind = op.get_bind()
    ids = bind.execute(sa.select(runs.c.id).where(runs.c.ga_state.is_not(None))).scalars().all()
    for run_id in ids:  # one state in memory at a time
        state = bind.execute(sa.select(runs.c.ga_state).where(runs.c.id == run_id)).scalar()
        if isinstance(state, dict) and state.get("archive") is not None:
            bind.execute(
                sa.update(runs).where(runs.c.id == run_id).values(archive=state["archive"])
            )


def downgrade() -> None:
    bind = op.get_bind()
    ids = bind.execute(sa.select(runs.c.id).where(runs.c.archive.is_not(None))).scalars().all()
    for run_id in ids:
        row = bind.execute(
            sa.select(runs.c.ga_state, runs.c.archive).where(runs.c.id == run_id)
        ).one()
        if isinstance(row.ga_state, dict):
            state = {**row.ga_state, "archive": row.archive}
            bind.execute(sa.update(runs).where(runs.c.id == run_id).values(ga_state=state))
    op.drop_column("runs", "archive")  # SQLite 3.35+ drops a column in place
