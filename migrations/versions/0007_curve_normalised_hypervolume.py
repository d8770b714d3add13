"""The normalised hypervolume of the curve (issue 51): each generation's hypervolume of the front
so far with every objective scaled from its reference (0) to its ideal (1), 0-1 (NULL for a run
without objectives, and for every generation committed before this revision: its front is gone).

Revision ID: 0007
Revises: 0006
Create Date: 2026-12-07
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0007"
down_revision = "0006"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column("generations", sa.Column("normalised_hypervolume", sa.Float, nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("generations") as table:
        table.drop_column("normalised_hypervolume")
