"""Quality-diversity columns of the curve: each generation's archive coverage and QD-score
(NULL for a run without descriptors, and for every generation committed before this revision).

Revision ID: 0002
Revises: 0001
Create Date: 2026-12-02
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0002"
down_revision = "0001"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("generations") as table:
        table.add_column(sa.Column("coverage", sa.Float, nullable=True))
        table.add_column(sa.Column("qd_score", sa.Float, nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("generations") as table:
        table.drop_column("qd_score")
        table.drop_column("coverage")
