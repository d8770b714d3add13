"""The database schema as SQLAlchemy 2.x models: runs, generations, individuals, sweeps.

Migrations (`migrations/versions/`) create the same tables without importing this module; a test
checks the two agree. Failed fitness is NULL with status `failed` (never 0). One row per
individual, unique on (run, generation, index), and fitness is only ever written to a `pending`
row, so a second fitness for the same individual is impossible.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any, ClassVar, cast

from sqlalchemy import (
    JSON,
    BigInteger,
    DateTime,
    Float,
    ForeignKey,
    Index,
    Integer,
    String,
    Table,
    Text,
    TypeDecorator,
    UniqueConstraint,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column

from softevo.core.status import IndividualStatus, RunStatus

#: The values the status columns hold (`softevo.core.status`).
RUN_STATUSES = tuple(RunStatus)
INDIVIDUAL_STATUSES = tuple(IndividualStatus)


class UTCDateTime(TypeDecorator[datetime]):
    """Timezone-aware UTC on the way out, also from SQLite (which keeps no zone)."""

    impl = DateTime(timezone=True)
    cache_ok = True

    def process_result_value(self, value: datetime | None, dialect: object) -> datetime | None:
        if value is not None and value.tzinfo is None:
            return value.replace(tzinfo=UTC)
        return value


class Base(DeclarativeBase):
    type_annotation_map: ClassVar[dict[Any, Any]] = {datetime: UTCDateTime}


class Sweep(Base):
    __tablename__ = "sweeps"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    request: Mapped[dict[str, Any]] = mapped_column(JSON)
    created_at: Mapped[datetime] = mapped_column()


class RunRow(Base):
    __tablename__ = "runs"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    sweep_id: Mapped[int | None] = mapped_column(ForeignKey("sweeps.id"), index=True)
    status: Mapped[str] = mapped_column(String(16), index=True)
    preset: Mapped[str | None] = mapped_column(String(64))
    seed: Mapped[int] = mapped_column(BigInteger().with_variant(Integer, "sqlite"))
    config: Mapped[dict[str, Any]] = mapped_column(JSON)
    ga_state: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    #: a quality-diversity run's archive (`Archive.to_json()`) as of its last committed
    #: generation, kept apart from the GA state so `GET /runs/{id}/archive` reads it alone
    archive: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    generations_done: Mapped[int] = mapped_column(Integer, default=0)
    generations_total: Mapped[int] = mapped_column(Integer)
    evaluations: Mapped[int] = mapped_column(Integer, default=0)
    saved: Mapped[int] = mapped_column(Integer, default=0)
    best_fitness: Mapped[float | None] = mapped_column(Float)
    best_generation: Mapped[int | None] = mapped_column(Integer)
    compute_seconds: Mapped[float] = mapped_column(Float, default=0.0)
    error: Mapped[str | None] = mapped_column(Text)
    created_at: Mapped[datetime] = mapped_column()
    started_at: Mapped[datetime | None] = mapped_column()
    finished_at: Mapped[datetime | None] = mapped_column()
    lease_owner: Mapped[str | None] = mapped_column(String(128))
    lease_expires: Mapped[float | None] = mapped_column(Float)  # unix time (s)
    takeovers: Mapped[int] = mapped_column(Integer, default=0)


class GenerationRow(Base):
    __tablename__ = "generations"
    __table_args__ = (UniqueConstraint("run_id", "generation", name="uq_generation"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    run_id: Mapped[int] = mapped_column(ForeignKey("runs.id", ondelete="CASCADE"))
    generation: Mapped[int] = mapped_column(Integer)
    best: Mapped[float | None] = mapped_column(Float)
    mean: Mapped[float | None] = mapped_column(Float)
    median: Mapped[float | None] = mapped_column(Float)
    min: Mapped[float | None] = mapped_column(Float)
    std: Mapped[float | None] = mapped_column(Float)
    best_so_far: Mapped[float | None] = mapped_column(Float)
    diversity: Mapped[float] = mapped_column(Float)
    size: Mapped[int] = mapped_column(Integer)
    failed: Mapped[int] = mapped_column(Integer)
    evaluations: Mapped[int] = mapped_column(Integer)
    saved: Mapped[int] = mapped_column(Integer)
    seconds: Mapped[float] = mapped_column(Float)  # wall time of this generation's evaluation
    coverage: Mapped[float | None] = mapped_column(Float)  # runs with an archive (descriptors)
    qd_score: Mapped[float | None] = mapped_column(Float)
    hypervolume: Mapped[float | None] = mapped_column(Float)  # runs with objectives
    front_size: Mapped[int | None] = mapped_column(Integer)
    normalised_hypervolume: Mapped[float | None] = mapped_column(Float)  # 0-1, from 0007 on
    committed_at: Mapped[datetime] = mapped_column()


class IndividualRow(Base):
    __tablename__ = "individuals"
    __table_args__ = (
        UniqueConstraint("run_id", "generation", "index", name="uq_individual"),
        Index("ix_individuals_run_hash", "run_id", "genome_hash"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    run_id: Mapped[int] = mapped_column(ForeignKey("runs.id", ondelete="CASCADE"))
    generation: Mapped[int] = mapped_column(Integer)
    index: Mapped[int] = mapped_column(Integer)
    genome: Mapped[dict[str, Any]] = mapped_column(JSON)
    genome_hash: Mapped[str] = mapped_column(String(32))
    operator: Mapped[str] = mapped_column(String(32))
    parents: Mapped[list[int]] = mapped_column(JSON)
    status: Mapped[str] = mapped_column(String(16), default=IndividualStatus.PENDING.value)
    fitness: Mapped[float | None] = mapped_column(Float)
    #: record of measures (name -> number or null, `SimResult.measures`); NULL while pending,
    #: {} for a robot that could not be built; rows from before revision 0004 hold the fitness
    #: under its measure's name and the heading
    measures: Mapped[dict[str, float | None] | None] = mapped_column(JSON)
    eval_seconds: Mapped[float | None] = mapped_column(Float)
    worker: Mapped[str | None] = mapped_column(String(128))
    evaluated_at: Mapped[datetime | None] = mapped_column()


# The rows' tables for Core statements (the driver's, run several times a generation, skip the
# ORM's per-statement work); `__table__` is typed as any FromClause, these are tables.
RUNS = cast(Table, RunRow.__table__)
GENERATIONS = cast(Table, GenerationRow.__table__)
INDIVIDUALS = cast(Table, IndividualRow.__table__)
#: `individuals.status` of an individual bred but not evaluated yet, as the statements write it
PENDING = IndividualStatus.PENDING.value
