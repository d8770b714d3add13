"""The coordinator's reads and writes while it drives a run: the run to drive, the fitness its
earlier generations already have, a generation's individuals (one multi-row insert), batches'
fitness (one statement for any number of batches) and the generation's commit (its fitness,
statistics, GA state and counters, and the next generation's members, all or nothing); each
individual's record of measures (`SimResult.measures`, a JSON object in `individuals.measures`)
is written and read beside its fitness. Every
write is fenced by the lease in its own transaction (`leases.owns`), so a coordinator that lost
the run can never write over its successor."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from sqlalchemy import Connection, bindparam, insert, select, update

from softevo.api.db import Database, EncodedJSON
from softevo.api.models import GENERATIONS, INDIVIDUALS, PENDING, RUNS, IndividualRow, RunRow
from softevo.api.store import leases
from softevo.api.store.fitness_rows import Landed, fitness_rows, set_fitness
from softevo.api.store.runs import now
from softevo.api.store.statements import DriverStatement
from softevo.core.nulls import from_null, from_null_record
from softevo.core.status import IndividualStatus, RunStatus

CURVE_FIELDS = (
    "generation",
    "best",
    "mean",
    "median",
    "min",
    "std",
    "best_so_far",
    "diversity",
    "size",
    "failed",
    "evaluations",
    "saved",
)


@dataclass(frozen=True)
class Lease:
    """Who drives (the coordinator's id) and for how long each write renews the lease (s)."""

    owner: str
    seconds: float


class LeaseLostError(RuntimeError):
    """This coordinator no longer owns the run (taken over, cancelled or finished)."""


class GenerationMismatchError(RuntimeError):
    """The stored generation is not the one the algorithm regenerated from the run's seed."""


def _fence(connection: Connection, run_id: int, lease: Lease) -> None:
    if not leases.owns(connection, run_id, lease.owner, lease.seconds):
        raise LeaseLostError(f"run {run_id}: lease lost or run no longer running")


def load(db: Database, run_id: int) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """The run's config and the GA state stored with its last committed generation, its
    archive (kept in a column of its own) put back in."""
    with db.read_session() as session:
        row = session.execute(
            select(RunRow.config, RunRow.ga_state, RunRow.archive).where(RunRow.id == run_id)
        ).one()
        if row.ga_state is None or row.archive is None:
            return row.config, row.ga_state
        return row.config, {**row.ga_state, "archive": row.archive}


def known_fitness(
    db: Database, run_id: int, before: int, since: int | None = None
) -> tuple[dict[str, float], dict[str, dict[str, float]]]:
    """Fitness (NaN = failed) of every genome evaluated in generations before `before` (and
    from `since` on, if given), and their records of measures (NaN = not measured; rows upgraded
    from before revision 0004 hold the fitness's measure and the heading), by genome hash."""
    where = [
        IndividualRow.run_id == run_id,
        IndividualRow.generation < before,
        IndividualRow.status != IndividualStatus.PENDING,
    ]
    if since is not None:
        where.append(IndividualRow.generation >= since)
    with db.read_session() as session:
        rows = session.execute(
            select(IndividualRow.genome_hash, IndividualRow.fitness, IndividualRow.measures).where(
                *where
            )
        ).all()
        fitness = {genome_hash: from_null(value) for genome_hash, value, _ in rows}
        return fitness, {genome_hash: from_null_record(record) for genome_hash, _, record in rows}


#: A birth asked and not written yet: (generation, index, member: genome, genome_hash, operator,
#: parents).
Member = tuple[int, int, dict[str, Any]]


@dataclass(frozen=True)
class GenerationCommit:
    """What one generation's commit writes, all or nothing: its statistics (`stats`:
    GenerationStats.to_json()), the GA state after it (`state`: its JSON, or its text as
    `EncodedJSON`), the fitness of members copied from earlier generations (`cached`), batches'
    fitness not saved yet (`landed`), the run's best (fitness, generation), the generation's wall
    time, and the births asked since the last write (`members`: the next row's too, so the next
    step needs no transaction of its own to keep them)."""

    stats: dict[str, Any]
    state: dict[str, Any] | EncodedJSON
    archive: dict[str, Any] | EncodedJSON | None = None  # a quality-diversity run's, apart
    cached: dict[int, float] = field(default_factory=dict)
    cached_measures: Mapping[int, Mapping[str, float]] = field(default_factory=dict)  # of `cached`
    landed: Sequence[Landed] = ()
    best: tuple[float, int] | None = None
    done: bool = False
    seconds: float = 0.0
    members: Sequence[Member] = ()  # births asked and not written yet


def save_fitness(
    db: Database,
    run_id: int,
    lease: Lease,
    generation: int,
    landed: Sequence[Landed],
    members: Sequence[Member] = (),
) -> None:
    """Batches' fitness, written once per individual, in one transaction (after the `members`
    asked since the last write)."""
    with db.write_connection() as connection:
        _fence(connection, run_id, lease)
        _insert_births(connection, run_id, members)
        rows = fitness_rows(run_id, generation, landed)
        set_fitness(connection, rows)


def _insert_births(connection: Connection, run_id: int, members: Sequence[Member]) -> None:
    """Births asked since the last write, one statement per generation."""
    by_generation: dict[int, dict[int, dict[str, Any]]] = {}
    for generation, index, member in members:
        by_generation.setdefault(generation, {})[index] = member
    for generation, by_index in by_generation.items():
        _insert_members(connection, run_id, generation, by_index)


MEMBER_COLUMNS = ("genome", "genome_hash", "operator", "parents")
_INSERT_MEMBER = DriverStatement(
    insert(INDIVIDUALS)
    .inline()
    .values(
        run_id=bindparam("b_run"),
        generation=bindparam("b_generation"),
        index=bindparam("b_index"),
        status=PENDING,
        **{column: bindparam(f"b_{column}") for column in MEMBER_COLUMNS},
    ),
    postgres_rows=f"""
    INSERT INTO individuals (run_id, generation, "index", status, genome, genome_hash, operator,
                             parents)
    SELECT %(b_run)s, %(b_generation)s, m.b_index, '{PENDING}', m.b_genome::json,
           m.b_genome_hash, m.b_operator, m.b_parents::json
    FROM ROWS FROM (json_to_recordset(%(b_rows)s::json) AS (b_index integer, b_genome text,
        b_genome_hash text, b_operator text, b_parents text)) WITH ORDINALITY
        AS m(b_index, b_genome, b_genome_hash, b_operator, b_parents, n)
    ORDER BY m.n""",
    scalars=("b_run", "b_generation"),
)


def _insert_members(
    connection: Connection,
    run_id: int,
    generation: int,
    members: Sequence[dict[str, Any]] | Mapping[int, dict[str, Any]],
) -> None:
    """Members of one generation: all of them in order, or some by index."""
    items = members.items() if isinstance(members, Mapping) else enumerate(members)
    _INSERT_MEMBER.execute(
        connection,
        [
            {
                "b_run": run_id,
                "b_generation": generation,
                "b_index": index,
                **{f"b_{column}": member[column] for column in MEMBER_COLUMNS},
            }
            for index, member in items
        ],
    )


# The run's row after a generation, precompiled (bound parameters, not literal values: the GA
# state is a large JSON value that would otherwise be walked for the statement's cache key).
# The best is the GA state's best so far, so writing it every time never lowers it.
_ADVANCE_STATEMENT = (
    update(RUNS)
    .where(RUNS.c.id == bindparam("b_run"))
    .values(
        ga_state=bindparam("b_state", type_=RUNS.c.ga_state.type),
        archive=bindparam("b_archive", type_=RUNS.c.archive.type),
        generations_done=bindparam("b_done"),
        evaluations=RUNS.c.evaluations + bindparam("b_evaluations"),
        saved=RUNS.c.saved + bindparam("b_saved"),
        compute_seconds=RUNS.c.compute_seconds + bindparam("b_seconds"),
        best_fitness=bindparam("b_best"),
        best_generation=bindparam("b_best_generation"),
    )
)
_ADVANCE = DriverStatement(_ADVANCE_STATEMENT)
_FINISH = DriverStatement(
    _ADVANCE_STATEMENT.values(
        status=RunStatus.COMPLETED.value,
        finished_at=bindparam("b_at"),
        lease_owner=None,
        lease_expires=None,
    )
)
_INSERT_GENERATION = DriverStatement(
    insert(GENERATIONS)
    .inline()
    .values(
        run_id=bindparam("b_run"),
        coverage=bindparam("b_coverage"),
        qd_score=bindparam("b_qd_score"),
        hypervolume=bindparam("b_hypervolume"),
        front_size=bindparam("b_front_size"),
        normalised_hypervolume=bindparam("b_normalised_hypervolume"),
        seconds=bindparam("b_seconds"),
        committed_at=bindparam("b_at"),
        **{key: bindparam(f"b_{key}") for key in CURVE_FIELDS},
    )
)


def commit_generation(db: Database, run_id: int, lease: Lease, commit: GenerationCommit) -> None:
    """The row's births asked since the last write (the next row's among them), its fitness,
    statistics, strategy state and counters, all or nothing."""
    stats = commit.stats
    generation = stats["generation"]
    best = (None, None) if commit.best is None else commit.best
    with db.write_connection() as connection:
        _fence(connection, run_id, lease)
        _insert_births(connection, run_id, commit.members)
        rows = fitness_rows(run_id, generation, commit.landed)
        cached = [Landed(commit.cached, None, None, commit.cached_measures)]
        rows += fitness_rows(run_id, generation, cached, IndividualStatus.CACHED)
        set_fitness(connection, rows)
        at = now()
        _INSERT_GENERATION.execute(
            connection,
            [
                {
                    "b_run": run_id,
                    **{f"b_{key}": stats[key] for key in CURVE_FIELDS},
                    "b_coverage": stats.get("coverage"),
                    "b_qd_score": stats.get("qd_score"),
                    "b_hypervolume": stats.get("hypervolume"),
                    "b_front_size": stats.get("front_size"),
                    "b_normalised_hypervolume": stats.get("normalised_hypervolume"),
                    "b_seconds": commit.seconds,
                    "b_at": at,
                }
            ],
        )
        advance = {
            "b_run": run_id,
            "b_state": commit.state,
            "b_archive": commit.archive,
            "b_done": generation + 1,
            "b_evaluations": stats["evaluations"],
            "b_saved": stats["saved"],
            "b_seconds": commit.seconds,
            "b_best": best[0],
            "b_best_generation": best[1],
        }
        if commit.done:
            _FINISH.execute(connection, [{**advance, "b_at": at}])
        else:
            _ADVANCE.execute(connection, [advance])


def fail(db: Database, run_id: int, owner: str, message: str) -> None:
    """The run failed for good (a bug, a broken evaluator): say why on it."""
    with db.write_session() as session:
        session.execute(
            update(RunRow)
            .where(RunRow.id == run_id, RunRow.lease_owner == owner)
            .values(
                status=RunStatus.FAILED.value,
                error=message[:2000],
                finished_at=now(),
                lease_owner=None,
                lease_expires=None,
            )
        )
