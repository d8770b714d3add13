"""The store's contract, one suite on SQLite and on PostgreSQL (the `db` fixture runs both): runs
queue and cancel only while active; births are kept with a write and read back by a successor;
a fitness is written once per individual; a commit is all or nothing; and a coordinator that
lost its lease can write nothing."""

from __future__ import annotations

import math

import pytest
from sqlalchemy import func, select
from sqlalchemy.exc import IntegrityError

from softevo.api import store
from softevo.api.db import Database
from softevo.api.models import GenerationRow, IndividualRow
from softevo.api.store.driving import (
    GenerationCommit,
    Landed,
    Lease,
    LeaseLostError,
)
from softevo.core.config import resolve
from softevo.core.status import IndividualStatus, RunStatus

REQUEST = {"preset": "quick", "population": 4, "generations": 2, "seed": 1}
OWNER = Lease("owner-a", 30.0)


def members(tag: str = "x") -> list[dict]:
    return [
        {
            "genome": {"discrete": [i], "real": []},
            "genome_hash": f"{tag}{i}",
            "operator": "random",
            "parents": [],
        }
        for i in range(4)
    ]


def keep(
    db: Database, run_id: int, generation: int, kept: list[dict], lease: Lease = OWNER
) -> None:
    """Births asked and written with a save, as a driver writes them."""
    births = [(generation, index, member) for index, member in enumerate(kept)]
    store.driving.save_fitness(db, run_id, lease, generation, [], births)


def driven(db: Database) -> int:
    run = store.create_run(db, resolve(REQUEST))
    assert store.leases.acquire(db, run.id, OWNER.owner, OWNER.seconds)
    return run.id


def statuses(db: Database, run_id: int) -> dict[int, tuple[str, float | None]]:
    with db.read_session() as session:
        rows = session.execute(
            select(IndividualRow.index, IndividualRow.status, IndividualRow.fitness).where(
                IndividualRow.run_id == run_id
            )
        )
        return {index: (status, fitness) for index, status, fitness in rows}


def test_births_are_kept_once_and_read_back_by_a_successor(db: Database) -> None:
    run_id = driven(db)
    keep(db, run_id, 0, members())
    assert len(statuses(db, run_id)) == 4
    with pytest.raises(IntegrityError):  # the same births twice
        keep(db, run_id, 0, members())
    stored = store.births.stored_births(db, run_id, 0)
    assert stored == {(0, i): (f"x{i}", None, {}) for i in range(4)}
    assert store.births.stored_births(db, run_id, 1) == {}


def test_a_fitness_is_written_once_and_nan_is_failed_not_zero(db: Database) -> None:
    run_id = driven(db)
    keep(db, run_id, 0, members())
    store.driving.save_fitness(db, run_id, OWNER, 0, [Landed({0: 0.5, 1: math.nan}, "w1", 0.1)])
    late_twin = Landed({0: 9.0}, "w2", 0.1)
    store.driving.save_fitness(db, run_id, OWNER, 0, [late_twin, Landed({2: 0.25}, "w3", 0.2)])
    assert statuses(db, run_id) == {
        0: (IndividualStatus.EVALUATED, 0.5),
        1: (IndividualStatus.FAILED, None),
        2: (IndividualStatus.EVALUATED, 0.25),
        3: (IndividualStatus.PENDING, None),
    }
    # what a successor reads back: fitness saved, NaN for the failed one, None: pending
    known = {key[1]: found[1] for key, found in store.births.stored_births(db, run_id, 0).items()}
    assert known[0] == 0.5 and math.isnan(known[1]) and known[2] == 0.25 and known[3] is None


STATS = {
    "generation": 0,
    "best": 0.5,
    "mean": 0.3,
    "median": 0.3,
    "min": 0.1,
    "std": 0.1,
    "best_so_far": 0.5,
    "diversity": 0.4,
    "size": 4,
    "failed": 0,
    "evaluations": 3,
    "saved": 1,
}


def commit(db: Database, run_id: int, lease: Lease, done: bool, **parts: object) -> None:
    store.driving.commit_generation(
        db,
        run_id,
        lease,
        GenerationCommit(
            STATS, {"seed": 1}, cached={3: 0.1}, best=(0.5, 0), done=done, seconds=1.5, **parts
        ),  # type: ignore[arg-type]
    )


def test_a_commit_writes_the_generation_counters_and_cached_fitness(db: Database) -> None:
    run_id = driven(db)
    keep(db, run_id, 0, members())
    commit(db, run_id, OWNER, done=True)
    record = store.get_run(db, run_id)
    assert record.status == RunStatus.COMPLETED and record.generations_done == 1
    assert (record.evaluations, record.saved, record.best_fitness) == (3, 1, 0.5)
    assert statuses(db, run_id)[3] == (IndividualStatus.CACHED, 0.1)
    assert [row["generation"] for row in store.curve(db, run_id)] == [0]


def test_a_commit_writes_what_landed_and_keeps_the_next_generation(db: Database) -> None:
    """Batches' fitness not saved yet lands with the commit, and the next generation's births
    are kept by it: a successor finds them, nothing evaluated."""
    run_id = driven(db)
    keep(db, run_id, 0, members())
    store.driving.save_fitness(db, run_id, OWNER, 0, [Landed({0: 0.5}, "w1", 0.1)])
    landed = [Landed({1: math.nan}, "w1", 0.1), Landed({2: 0.25}, "w2", 0.3)]
    upcoming = [(1, index, member) for index, member in enumerate(members("n"))]
    commit(db, run_id, OWNER, done=False, landed=landed, members=upcoming)
    columns = (
        IndividualRow.genome_hash,
        IndividualRow.status,
        IndividualRow.fitness,
        IndividualRow.worker,
    )
    with db.read_session() as session:
        rows = session.execute(
            select(*columns)
            .where(IndividualRow.run_id == run_id)
            .order_by(IndividualRow.generation, IndividualRow.index)
        ).all()
    assert [tuple(row) for row in rows[:4]] == [
        ("x0", IndividualStatus.EVALUATED, 0.5, "w1"),
        ("x1", IndividualStatus.FAILED, None, "w1"),
        ("x2", IndividualStatus.EVALUATED, 0.25, "w2"),
        ("x3", IndividualStatus.CACHED, 0.1, None),
    ]
    assert [tuple(row) for row in rows[4:]] == [
        (f"n{i}", IndividualStatus.PENDING, None, None) for i in range(4)
    ]
    stored = store.births.stored_births(db, run_id, 1)
    assert stored == {(1, i): (f"n{i}", None, {}) for i in range(4)}
    assert store.get_run(db, run_id).generations_done == 1


def test_a_commit_is_all_or_nothing(db: Database) -> None:
    run_id = driven(db)
    keep(db, run_id, 0, members())
    commit(db, run_id, OWNER, done=False)
    with pytest.raises(IntegrityError):  # the same generation twice
        commit(db, run_id, OWNER, done=True)
    record = store.get_run(db, run_id)
    assert record.status == RunStatus.RUNNING and record.evaluations == 3  # not 6
    with db.read_session() as session:
        assert session.scalar(select(func.count()).select_from(GenerationRow)) == 1


def test_a_coordinator_that_lost_its_lease_writes_nothing(db: Database) -> None:
    run_id = driven(db)
    keep(db, run_id, 0, members())
    store.leases.release_all(db, OWNER.owner)
    successor = Lease("owner-b", 30.0)
    assert store.leases.acquire(db, run_id, successor.owner, successor.seconds)
    for write in (
        lambda: keep(db, run_id, 1, members("z")),
        lambda: store.driving.save_fitness(db, run_id, OWNER, 0, [Landed({0: 1.0}, "old", 0.1)]),
        lambda: commit(db, run_id, OWNER, done=True),
    ):
        with pytest.raises(LeaseLostError):
            write()
    assert statuses(db, run_id)[0] == (IndividualStatus.PENDING, None)
    assert store.get_run(db, run_id).status == RunStatus.RUNNING


def test_cancel_changes_only_an_active_run(db: Database) -> None:
    queued = store.create_run(db, resolve(REQUEST))
    assert store.cancel_run(db, queued.id).status == RunStatus.CANCELLED
    with pytest.raises(store.ConflictError, match="is cancelled"):
        store.cancel_run(db, queued.id)
    run_id = driven(db)
    keep(db, run_id, 0, members())
    commit(db, run_id, OWNER, done=True)
    with pytest.raises(store.ConflictError, match="is completed"):
        store.cancel_run(db, run_id)
    assert store.get_run(db, run_id).status == RunStatus.COMPLETED
    with pytest.raises(store.NotFoundError, match="run 999 not found"):
        store.cancel_run(db, 999)
