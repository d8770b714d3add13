"""The measured heading of every evaluated individual (degrees, `SimResult.heading`), which the
behavioural `heading` descriptor of MAP-Elites needs, stored with its fitness so a run taken over
after a crash rebuilds the same archive. NULL for failed robots and every individual stored
before this revision.

Revision ID: 0003
Revises: 0002
Create Date: 2026-12-02
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("individuals") as table:
        table.add_column(sa.Column("heading", sa.Float, nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("individuals") as table:
        table.drop_column("heading")
