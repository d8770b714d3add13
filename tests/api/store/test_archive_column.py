"""A quality-diversity run's archive in its own column (revision 0005), on SQLite and
PostgreSQL: a commit writes it apart from the GA state, `store.archive` reads it alone and the
coordinator's `load` puts it back into the state; a database of the release before (the archive
inside the GA state) is upgraded with its archive moved to the column, and downgraded with it
put back."""

from __future__ import annotations

import json

from sqlalchemy import text

from softevo.api import store
from softevo.api.db import Database
from softevo.api.store.driving import GenerationCommit
from tests.api.store.test_measures_store import downgrade
from tests.api.store.test_store import OWNER, STATS, driven, keep, members

ARCHIVE = {
    "descriptors": ["voxels"],
    "bins": [4],
    "elites": [
        {
            "cell": [1],
            "values": [0.3],
            "fitness": 0.25,
            "generation": 0,
            "index": 2,
            "genome": {"discrete": [1, 0], "real": []},
        }
    ],
}


def stored_state(db: Database, run_id: int) -> dict:
    with db.engine.connect() as connection:
        found = connection.execute(text(f"SELECT ga_state FROM runs WHERE id = {run_id}")).scalar()
    return found if isinstance(found, dict) else json.loads(found)


def test_a_commit_writes_the_archive_apart_and_load_puts_it_back(db: Database) -> None:
    run_id = driven(db)
    assert store.archive(db, run_id) is None  # before the first commit
    keep(db, run_id, 0, members())
    commit = GenerationCommit(
        STATS,
        {"seed": 1},
        archive=ARCHIVE,
        best=(0.25, 0),
        members=[(1, i, m) for i, m in enumerate(members("n"))],
    )
    store.driving.commit_generation(db, run_id, OWNER, commit)
    assert store.archive(db, run_id) == ARCHIVE
    assert "archive" not in stored_state(db, run_id)
    assert store.driving.load(db, run_id)[1] == {"seed": 1, "archive": ARCHIVE}


def test_an_archive_inside_the_state_moves_to_its_column_and_back(db: Database) -> None:
    run_id = driven(db)
    keep(db, run_id, 0, members())
    kept = store.progress_counts(db, run_id)
    downgrade(db, "0004")  # the release before: the archive inside the GA state
    with db.engine.begin() as connection:
        connection.execute(
            text("UPDATE runs SET ga_state = :state WHERE id = :id"),
            {"state": json.dumps({"seed": 1, "archive": ARCHIVE}), "id": run_id},
        )
    db.upgrade()
    assert store.archive(db, run_id) == ARCHIVE
    assert store.driving.load(db, run_id)[1] == {"seed": 1, "archive": ARCHIVE}
    with db.engine.begin() as connection:  # as a commit after the upgrade leaves it
        connection.execute(
            text("UPDATE runs SET ga_state = :state WHERE id = :id"),
            {"state": json.dumps({"seed": 1}), "id": run_id},
        )
    downgrade(db, "0004")
    assert stored_state(db, run_id) == {"seed": 1, "archive": ARCHIVE}
    db.upgrade()
    assert kept and store.progress_counts(db, run_id) == kept  # no individual lost on the way
