"""Pareto columns of the curve (issue 36): each generation's hypervolume of the front so far and
that front's size (NULL for a run without objectives, and for every generation committed before
this revision).

Revision ID: 0006
Revises: 0005
Create Date: 2026-12-05
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0006"
down_revision = "0005"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column("generations", sa.Column("hypervolume", sa.Float, nullable=True))
    op.add_column("generations", sa.Column("front_size", sa.Integer, nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("generations") as table:
        table.drop_column("front_size")
        table.drop_column("hypervolume")
