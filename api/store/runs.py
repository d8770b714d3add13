"""Reads and writes of runs, sweeps, generations and individuals for the API.

ORM rows are turned into plain frozen values here (`RunRecord`, dicts of JSON-safe values), so
no session or lazy attribute ever leaks into a route. The coordinator's own writes (leases,
fitness, generation commits) live beside this module, in `leases` and `driving`.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

import numpy as np
from sqlalchemy import func, select, update
from sqlalchemy.orm import defer

from softevo.api.db import Database, rowcount
from softevo.api.models import GenerationRow, IndividualRow, RunRow, Sweep
from softevo.core.config import RunConfig
from softevo.core.nulls import to_null
from softevo.core.search.stats import CURVE_COLUMNS
from softevo.core.status import ACTIVE, RunStatus


def now() -> datetime:
    return datetime.now(UTC)


class NotFoundError(LookupError):
    """An unknown id; the message names it."""


class ConflictError(RuntimeError):
    """An action the run's state forbids."""


class QueueFullError(RuntimeError):
    """Queuing would take the waiting runs past their bound (SOFTEVO_MAX_QUEUED)."""


QUEUE_LOCK = 0x50F7E0  # PostgreSQL advisory lock: one queuing transaction at a time


def _make_room(session: Any, wanted: int, max_queued: int | None) -> None:
    """Refuse `wanted` more runs if the queue would pass `max_queued`; counted inside the write
    transaction, under a lock on PostgreSQL (SQLite's BEGIN IMMEDIATE already serialises)."""
    if max_queued is None:
        return
    if session.get_bind().dialect.name == "postgresql":
        session.execute(select(func.pg_advisory_xact_lock(QUEUE_LOCK)))
    queued = session.scalar(
        select(func.count()).select_from(RunRow).where(RunRow.status == RunStatus.QUEUED)
    )
    if queued + wanted > max_queued:
        raise QueueFullError(
            f"{queued} runs are waiting and {wanted} more would pass the bound of {max_queued} "
            "(SOFTEVO_MAX_QUEUED); try again when some have started"
        )


@dataclass(frozen=True)
class RunRecord:
    id: int
    status: str
    preset: str | None
    seed: int
    config: dict[str, Any]
    sweep_id: int | None
    generations_done: int
    generations_total: int
    evaluations: int
    saved: int
    best_fitness: float | None
    best_generation: int | None
    compute_seconds: float
    error: str | None
    created_at: datetime
    started_at: datetime | None
    finished_at: datetime | None
    takeovers: int


#: Runs as reads see them: never the GA state (two populations of JSON, only the coordinator's)
#: nor the archive (read alone by `archive`).
_RUNS = select(RunRow).options(
    defer(RunRow.ga_state, raiseload=True), defer(RunRow.archive, raiseload=True)
)


def _record(row: RunRow) -> RunRecord:
    return RunRecord(
        id=row.id,
        status=row.status,
        preset=row.preset,
        seed=row.seed,
        config=row.config,
        sweep_id=row.sweep_id,
        generations_done=row.generations_done,
        generations_total=row.generations_total,
        evaluations=row.evaluations,
        saved=row.saved,
        best_fitness=row.best_fitness,
        best_generation=row.best_generation,
        compute_seconds=row.compute_seconds,
        error=row.error,
        created_at=row.created_at,
        started_at=row.started_at,
        finished_at=row.finished_at,
        takeovers=row.takeovers,
    )


def _new_run(config: RunConfig, sweep_id: int | None = None) -> RunRow:
    return RunRow(
        sweep_id=sweep_id,
        status=RunStatus.QUEUED.value,
        preset=config.preset,
        seed=config.seed,
        config=config.to_json(),
        ga_state=None,
        generations_done=0,
        generations_total=config.generations,
        evaluations=0,
        saved=0,
        compute_seconds=0.0,
        created_at=now(),
        takeovers=0,
    )


def create_run(db: Database, config: RunConfig, max_queued: int | None = None) -> RunRecord:
    with db.write_session() as session:
        _make_room(session, 1, max_queued)
        row = _new_run(config)
        session.add(row)
        session.flush()
        return _record(row)


def create_sweep(
    db: Database, request: dict[str, Any], configs: list[RunConfig], max_queued: int | None = None
) -> tuple[int, list[int]]:
    """One sweep row and its runs, all in one transaction (all queued, or none)."""
    with db.write_session() as session:
        _make_room(session, len(configs), max_queued)
        sweep = Sweep(request=request, created_at=now())
        session.add(sweep)
        session.flush()
        rows = [_new_run(config, sweep.id) for config in configs]
        session.add_all(rows)
        session.flush()
        return sweep.id, [row.id for row in rows]


def get_run(db: Database, run_id: int) -> RunRecord:
    with db.read_session() as session:
        row = session.scalar(_RUNS.where(RunRow.id == run_id))
        if row is None:
            raise NotFoundError(f"run {run_id} not found")
        return _record(row)


def list_runs(
    db: Database, status: str | None, offset: int, limit: int
) -> tuple[list[RunRecord], int]:
    with db.read_session() as session:
        where = [] if status is None else [RunRow.status == status]
        total = session.scalar(select(func.count(RunRow.id)).where(*where)) or 0
        rows = session.scalars(
            _RUNS.where(*where).order_by(RunRow.id.desc()).offset(offset).limit(limit)
        )
        return [_record(row) for row in rows], total


def cancel_run(db: Database, run_id: int) -> RunRecord:
    """Queued or running -> cancelled, at once; results so far are kept. 409 otherwise. One
    conditional update: a run that completes at the same moment stays completed."""
    active = [status.value for status in ACTIVE]
    with db.write_session() as session:
        changed = rowcount(
            session.execute(
                update(RunRow)
                .where(RunRow.id == run_id, RunRow.status.in_(active))
                .values(
                    status=RunStatus.CANCELLED.value,
                    finished_at=now(),
                    lease_owner=None,
                    lease_expires=None,
                )
            )
        )
        if changed != 1:
            status = session.scalar(select(RunRow.status).where(RunRow.id == run_id))
            if status is None:
                raise NotFoundError(f"run {run_id} not found")
            raise ConflictError(f"run {run_id} is {status}; only queued or running runs cancel")
    return get_run(db, run_id)


def curve(db: Database, run_id: int) -> list[dict[str, Any]]:
    """Committed generations in order, with the columns of `CURVE_COLUMNS`."""
    with db.read_session() as session:
        rows = session.scalars(
            select(GenerationRow)
            .where(GenerationRow.run_id == run_id)
            .order_by(GenerationRow.generation)
        )
        return [_curve_row(row) for row in rows]


def _curve_row(row: GenerationRow) -> dict[str, Any]:
    """The row of `CURVE_COLUMNS`, `QD_COLUMNS` for a run with an archive and
    `PARETO_COLUMNS` for one with objectives."""
    data = {column: getattr(row, column) for column in CURVE_COLUMNS}
    if row.coverage is not None:
        data.update(coverage=row.coverage, qd_score=row.qd_score)
    if row.front_size is not None:
        data.update(hypervolume=row.hypervolume, front_size=row.front_size)
    if row.normalised_hypervolume is not None:  # none before revision 0007
        data["normalised_hypervolume"] = row.normalised_hypervolume
    return data


def curve_after(db: Database, run_id: int, after: int) -> list[dict[str, Any]]:
    """The committed generations after `after`, in order (what an event stream has not sent)."""
    with db.read_session() as session:
        rows = session.scalars(
            select(GenerationRow)
            .where(GenerationRow.run_id == run_id, GenerationRow.generation > after)
            .order_by(GenerationRow.generation)
        )
        return [_curve_row(row) for row in rows]


def individual_json(row: IndividualRow, population: int) -> dict[str, Any]:
    return {
        "id": row.generation * population + row.index,
        "generation": row.generation,
        "index": row.index,
        "fitness": to_null(row.fitness),
        "status": row.status,
        "measures": row.measures,
        "operator": row.operator,
        "parents": row.parents,
        "genome_hash": row.genome_hash,
        "eval_seconds": row.eval_seconds,
        "worker": row.worker,
    }


#: Individuals as listings see them: never the genome (tens of kB of JSON each; a page of 5000
#: with them cost 340 MB and 3 s, BENCHMARKS.md "Reads of a large run").
_LISTED = select(IndividualRow).options(defer(IndividualRow.genome, raiseload=True))


def list_individuals(
    db: Database, run: RunRecord, generation: int | None, offset: int, limit: int
) -> tuple[list[dict[str, Any]], int]:
    population = run.config["population"]
    where = [IndividualRow.run_id == run.id]
    if generation is not None:
        where.append(IndividualRow.generation == generation)
    with db.read_session() as session:
        total = session.scalar(select(func.count(IndividualRow.id)).where(*where)) or 0
        rows = session.scalars(
            _LISTED.where(*where)
            .order_by(IndividualRow.generation, IndividualRow.index)
            .offset(offset)
            .limit(limit)
        )
        return [individual_json(row, population) for row in rows], total


#: Rows read at a time by `population_points`.
CHUNK = 10_000


def population_points(db: Database, run_id: int) -> tuple[np.ndarray, np.ndarray]:
    """Every individual's generation and fitness (NaN: failed or not yet evaluated), in order:
    the dot plot's two columns as arrays (16 bytes an individual), read CHUNK rows at a time,
    never the rows' other columns."""
    with db.read_session() as session:
        size = (
            session.scalar(
                select(func.count(IndividualRow.id)).where(IndividualRow.run_id == run_id)
            )
            or 0
        )
        generations, fitness = np.zeros(size, dtype=np.int64), np.full(size, np.nan)
        result = session.execute(
            select(IndividualRow.generation, IndividualRow.fitness)
            .where(IndividualRow.run_id == run_id)
            .order_by(IndividualRow.generation, IndividualRow.index)
            .execution_options(yield_per=CHUNK)
        )
        done = 0
        for chunk in result.partitions():  # rows inserted since the count are left out
            block = np.array(chunk[: size - done], dtype=float).reshape(-1, 2)  # None -> NaN
            generations[done : done + len(block)] = block[:, 0]
            fitness[done : done + len(block)] = block[:, 1]
            done += len(block)
        return generations[:done], fitness[:done]


def get_individual(db: Database, run: RunRecord, number: int) -> dict[str, Any]:
    """Individual `number` = generation * population + index, with its genome."""
    population = run.config["population"]
    generation, index = divmod(number, population)
    with db.read_session() as session:
        row = session.scalar(
            select(IndividualRow).where(
                IndividualRow.run_id == run.id,
                IndividualRow.generation == generation,
                IndividualRow.index == index,
            )
        )
        if row is None:
            raise NotFoundError(f"run {run.id} has no individual {number}")
        return {**individual_json(row, population), "genome": row.genome}


def get_sweep(db: Database, sweep_id: int) -> tuple[dict[str, Any], list[RunRecord]]:
    with db.read_session() as session:
        sweep = session.get(Sweep, sweep_id)
        if sweep is None:
            raise NotFoundError(f"sweep {sweep_id} not found")
        rows = session.scalars(_RUNS.where(RunRow.sweep_id == sweep_id).order_by(RunRow.id))
        return {"id": sweep.id, "request": sweep.request, "created_at": sweep.created_at}, [
            _record(row) for row in rows
        ]


def list_sweeps(
    db: Database, offset: int, limit: int
) -> tuple[list[tuple[dict[str, Any], list[RunRecord]]], int]:
    """Newest first: each sweep and its runs."""
    with db.read_session() as session:
        total = session.scalar(select(func.count(Sweep.id))) or 0
        newest = select(Sweep.id).order_by(Sweep.id.desc())
        ids = list(session.scalars(newest.offset(offset).limit(limit)))
    return [get_sweep(db, sweep_id) for sweep_id in ids], total


def progress_counts(db: Database, run_id: int) -> dict[str, int]:
    """Individuals by status (fitness saved so far, also of the generation in progress)."""
    with db.read_session() as session:
        rows = session.execute(
            select(IndividualRow.status, func.count())
            .where(IndividualRow.run_id == run_id)
            .group_by(IndividualRow.status)
        )
        return {status: count for status, count in rows}


def best_individual(db: Database, run: RunRecord) -> dict[str, Any] | None:
    """The run's fastest individual so far (the GA's best: the first of its generation with the
    best fitness), with its genome; None before a generation is committed."""
    if run.best_generation is None or run.best_fitness is None:
        return None
    with db.read_session() as session:
        row = session.scalar(
            select(IndividualRow)
            .where(
                IndividualRow.run_id == run.id,
                IndividualRow.generation == run.best_generation,
                IndividualRow.fitness == run.best_fitness,
            )
            .order_by(IndividualRow.index)
            .limit(1)
        )
        if row is None:
            return None
        return {**individual_json(row, run.config["population"]), "genome": row.genome}


def archive(db: Database, run_id: int) -> dict[str, Any] | None:
    """The run's quality-diversity archive as of its last committed generation
    (`softevo.core.search.archive.Archive.to_json()`), from its own column, never the GA state;
    None before the first commit."""
    with db.read_session() as session:
        return session.scalar(select(RunRow.archive).where(RunRow.id == run_id))
