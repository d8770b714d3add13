"""The store as `softevo run` keeps it: one run in a SQLite file of its output folder, driven
by this process alone. What the service never needs lives here: which run the folder holds, a
lease taken without waiting for the last one to expire (the process that held it stopped), more
generations for a stopped run, its rows as population.csv lists them, and the import of a folder
written before the store (its files become the run's rows)."""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

from sqlalchemy import Connection, func, insert, inspect, select, update

from softevo.api.db import Database, EncodedJSON
from softevo.api.models import GENERATIONS, INDIVIDUALS, GenerationRow, IndividualRow, RunRow
from softevo.api.store.driving import CURVE_FIELDS
from softevo.api.store.runs import now
from softevo.core.config import RunConfig
from softevo.core.nulls import record_text, to_null
from softevo.core.search.state import StrategyState
from softevo.core.status import IndividualStatus, RunStatus

#: The generation of the fitness cache an imported folder brings (its genomes' generations are
#: not in its files): before every generation, so the run's reads count it as known.
IMPORTED = -1


def check_store(db: Database) -> None:
    """ValueError for a database that holds tables but is not softevo's (no Alembic version):
    migrating it would write softevo's tables into another program's file."""
    tables = inspect(db.engine).get_table_names()
    if tables and "alembic_version" not in tables:
        raise ValueError(f"holds other tables ({', '.join(sorted(tables)[:3])})")


def checkpoint(db: Database) -> None:
    """Move SQLite's write-ahead log into the database file, so the folder's run.db is whole
    by itself (a copy of it alone is the run)."""
    with db.engine.connect() as connection:
        connection.exec_driver_sql("PRAGMA wal_checkpoint(TRUNCATE)")


def the_run(db: Database) -> int | None:
    """The id of the folder's run (None: none yet)."""
    with db.read_session() as session:
        return session.scalar(select(func.min(RunRow.id)))


def take(db: Database, run_id: int, owner: str, seconds: float, generations: int) -> None:
    """Drive the run to `generations` from now on, whoever held it: a folder's run is driven by
    the one process that opened it (the lease still fences every write, so a second one that
    takes it stops the first)."""
    config = db_config(db, run_id)
    finished = totals(db, run_id)[0] >= generations
    with db.write_session() as session:
        session.execute(
            update(RunRow)
            .where(RunRow.id == run_id)
            .values(
                status=(RunStatus.COMPLETED if finished else RunStatus.RUNNING).value,
                lease_owner=owner,
                lease_expires=now().timestamp() + seconds,
                config={**config, "generations": generations},
                generations_total=generations,
                error=None,
                finished_at=now() if finished else None,
            )
        )


def release(db: Database, run_id: int, owner: str) -> None:
    """Give the lease back (stopped or finished): the next `take` finds the run free."""
    with db.write_session() as session:
        session.execute(
            update(RunRow)
            .where(RunRow.id == run_id, RunRow.lease_owner == owner)
            .values(lease_expires=0.0)
        )


def db_config(db: Database, run_id: int) -> dict[str, Any]:
    with db.read_session() as session:
        config = session.scalar(select(RunRow.config).where(RunRow.id == run_id))
    if config is None:
        raise KeyError(run_id)
    return dict(config)


def totals(db: Database, run_id: int) -> tuple[int, int, int, float]:
    """(generations done, evaluations, saved, compute seconds) of the run."""
    with db.read_session() as session:
        row = session.execute(
            select(
                RunRow.generations_done, RunRow.evaluations, RunRow.saved, RunRow.compute_seconds
            ).where(RunRow.id == run_id)
        ).one()
        return row.generations_done, row.evaluations, row.saved, row.compute_seconds


_OPTIONAL = ("coverage", "qd_score", "hypervolume", "front_size", "normalised_hypervolume")


def history(db: Database, run_id: int) -> list[dict[str, Any]]:
    """The committed generations' statistics in order, every field (`GenerationStats.to_json`'s:
    the API's curve leaves some out); a column of a kind the run has not left out."""
    columns = [getattr(GenerationRow, name) for name in (*CURVE_FIELDS, *_OPTIONAL)]
    with db.read_session() as session:
        rows = session.execute(
            select(*columns)
            .where(GenerationRow.run_id == run_id)
            .order_by(GenerationRow.generation)
        )
        return [
            {
                key: value
                for key, value in row._mapping.items()
                if value is not None or key not in _OPTIONAL
            }
            for row in rows
        ]


def population(db: Database, run_id: int, before: int, after: int = -1) -> Iterator[Any]:
    """Rows (generation, index, fitness, operator, measures) of the generations after `after`
    and before `before` (committed ones), in order: population.csv's rows."""
    columns = (
        IndividualRow.generation,
        IndividualRow.index,
        IndividualRow.fitness,
        IndividualRow.operator,
        IndividualRow.measures,
    )
    with db.read_session() as session:
        yield from session.execute(
            select(*columns)
            .where(
                IndividualRow.run_id == run_id,
                IndividualRow.generation > max(after, IMPORTED),
                IndividualRow.generation < before,
            )
            .order_by(IndividualRow.generation, IndividualRow.index)
        )


def import_run(
    db: Database,
    config: RunConfig,
    state: StrategyState,
    known: tuple[Mapping[str, float], Mapping[str, Mapping[str, float]]],
    elapsed: float,
    rows: Sequence[dict[str, Any]],
) -> int:
    """A run from a folder written before the store: its config, GA state (the curve from its
    history), fitness cache and measures by genome hash (`known`, rows of generation
    `IMPORTED`) and population.csv's `rows` (generation, index, fitness, operator, measures:
    their genomes are not in the files, so each keeps an empty one and no hash)."""
    with db.write_session() as session:
        run = _imported_run(config, state, elapsed)
        session.add(run)
        session.flush()
        connection = session.connection()
        _insert_curve(connection, run.id, state)
        _insert_individuals(connection, run.id, known, rows)
        return run.id


def _imported_run(config: RunConfig, state: StrategyState, elapsed: float) -> RunRow:
    """The run's row, running (the import finishes it), with the curve's totals."""
    history = state.history
    best = state.best
    return RunRow(
        status=RunStatus.RUNNING.value,
        preset=config.preset,
        seed=config.seed,
        config=config.to_json(),
        generations_done=state.generation,
        generations_total=config.generations,
        evaluations=sum(s.evaluations for s in history),
        saved=sum(s.saved for s in history),
        compute_seconds=elapsed,
        created_at=now(),
        started_at=now(),
        takeovers=0,
        ga_state=json.loads(state.to_text(history=False, archive=False)),
        archive=None if state.archive is None else state.archive.to_json(),
        best_fitness=None if best is None else best[1],
        best_generation=None if best is None else best[2],
    )


def _insert_curve(connection: Connection, run_id: int, state: StrategyState) -> None:
    """The curve's rows from the state's history."""
    if not state.history:
        return
    connection.execute(
        insert(GENERATIONS),
        [
            {
                "run_id": run_id,
                **{key: row.get(key) for key in (*CURVE_FIELDS, *_OPTIONAL)},
                "seconds": 0.0,
                "committed_at": now(),
            }
            for row in (stats.to_json() for stats in state.history)
        ],
    )


def _insert_individuals(
    connection: Connection,
    run_id: int,
    known: tuple[Mapping[str, float], Mapping[str, Mapping[str, float]]],
    rows: Sequence[dict[str, Any]],
) -> None:
    """The cache's genomes (generation `IMPORTED`) and population.csv's rows, without genomes."""
    fitness, measures = known
    cached = [
        (IMPORTED, number, key, fitness[key], "imported", measures.get(key, {}))
        for number, key in enumerate(sorted(fitness))
    ]
    listed = [
        (row["generation"], row["index"], "", row["fitness"], row["operator"], row["measures"])
        for row in rows
    ]
    if not (cached or listed):
        return
    connection.execute(
        insert(INDIVIDUALS),
        [
            {
                "run_id": run_id,
                "generation": generation,
                "index": index,
                "genome": EncodedJSON("{}"),
                "genome_hash": key,
                "operator": operator[:32],
                "parents": EncodedJSON("[]"),
                "fitness": to_null(value),
                "measures": EncodedJSON(record_text(record)),
                "evaluated_at": now(),
                "status": (
                    IndividualStatus.EVALUATED
                    if to_null(value) is not None
                    else IndividualStatus.FAILED
                ).value,
            }
            for generation, index, key, value, operator, record in cached + listed
        ],
    )
