"""Initial schema: sweeps, runs, generations, individuals.

Revision ID: 0001
Revises:
Create Date: 2026-11-23
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0001"
down_revision = None
branch_labels = None
depends_on = None

TZ = sa.DateTime(timezone=True)


def upgrade() -> None:
    _sweeps_and_runs()
    _generations_and_individuals()


def _sweeps_and_runs() -> None:
    op.create_table(
        "sweeps",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("request", sa.JSON, nullable=False),
        sa.Column("created_at", TZ, nullable=False),
    )
    op.create_table(
        "runs",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column("sweep_id", sa.Integer, sa.ForeignKey("sweeps.id"), nullable=True),
        sa.Column("status", sa.String(16), nullable=False),
        sa.Column("preset", sa.String(64), nullable=True),
        sa.Column("seed", sa.BigInteger().with_variant(sa.Integer, "sqlite"), nullable=False),
        sa.Column("config", sa.JSON, nullable=False),
        sa.Column("ga_state", sa.JSON, nullable=True),
        sa.Column("generations_done", sa.Integer, nullable=False),
        sa.Column("generations_total", sa.Integer, nullable=False),
        sa.Column("evaluations", sa.Integer, nullable=False),
        sa.Column("saved", sa.Integer, nullable=False),
        sa.Column("best_fitness", sa.Float, nullable=True),
        sa.Column("best_generation", sa.Integer, nullable=True),
        sa.Column("compute_seconds", sa.Float, nullable=False),
        sa.Column("error", sa.Text, nullable=True),
        sa.Column("created_at", TZ, nullable=False),
        sa.Column("started_at", TZ, nullable=True),
        sa.Column("finished_at", TZ, nullable=True),
        sa.Column("lease_owner", sa.String(128), nullable=True),
        sa.Column("lease_expires", sa.Float, nullable=True),
        sa.Column("takeovers", sa.Integer, nullable=False),
    )
    op.create_index("ix_runs_status", "runs", ["status"])
    op.create_index("ix_runs_sweep_id", "runs", ["sweep_id"])


def _generations_and_individuals() -> None:
    op.create_table(
        "generations",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column(
            "run_id", sa.Integer, sa.ForeignKey("runs.id", ondelete="CASCADE"), nullable=False
        ),
        sa.Column("generation", sa.Integer, nullable=False),
        *(
            sa.Column(name, sa.Float, nullable=True)
            for name in ("best", "mean", "median", "min", "std", "best_so_far")
        ),
        sa.Column("diversity", sa.Float, nullable=False),
        sa.Column("size", sa.Integer, nullable=False),
        sa.Column("failed", sa.Integer, nullable=False),
        sa.Column("evaluations", sa.Integer, nullable=False),
        sa.Column("saved", sa.Integer, nullable=False),
        sa.Column("seconds", sa.Float, nullable=False),
        sa.Column("committed_at", TZ, nullable=False),
        sa.UniqueConstraint("run_id", "generation", name="uq_generation"),
    )
    op.create_table(
        "individuals",
        sa.Column("id", sa.Integer, primary_key=True),
        sa.Column(
            "run_id", sa.Integer, sa.ForeignKey("runs.id", ondelete="CASCADE"), nullable=False
        ),
        sa.Column("generation", sa.Integer, nullable=False),
        sa.Column("index", sa.Integer, nullable=False),
        sa.Column("genome", sa.JSON, nullable=False),
        sa.Column("genome_hash", sa.String(32), nullable=False),
        sa.Column("operator", sa.String(32), nullable=False),
        sa.Column("parents", sa.JSON, nullable=False),
        sa.Column("status", sa.String(16), nullable=False),
        sa.Column("fitness", sa.Float, nullable=True),
        sa.Column("eval_seconds", sa.Float, nullable=True),
        sa.Column("worker", sa.String(128), nullable=True),
        sa.Column("evaluated_at", TZ, nullable=True),
        sa.UniqueConstraint("run_id", "generation", "index", name="uq_individual"),
    )
    op.create_index("ix_individuals_run_hash", "individuals", ["run_id", "genome_hash"])


def downgrade() -> None:
    op.drop_table("individuals")
    op.drop_table("generations")
    op.drop_table("runs")
    op.drop_table("sweeps")
