"""The curve's `normalised_hypervolume` in its own column (revision 0007), on SQLite and
PostgreSQL: a commit writes it beside the raw hypervolume and the curve and the folder's history
read it back; a generation committed before the revision reads without it (and keeps every other
column) through a downgrade and an upgrade; a config stored before objectives had an ideal
loads with the measures' defaults filled in."""

from __future__ import annotations

from sqlalchemy import update

from softevo.api import store
from softevo.api.db import Database
from softevo.api.models import RunRow
from softevo.api.store.driving import GenerationCommit
from softevo.api.store.folders import history
from softevo.core.config import RunConfig, resolve
from softevo.core.objectives import MEASURES
from tests.api.store.test_measures_store import downgrade
from tests.api.store.test_store import OWNER, REQUEST, STATS, driven, keep, members

PARETO = {"hypervolume": 37.5, "front_size": 3, "normalised_hypervolume": 0.7933884297520661}


def committed(db: Database, stats: dict) -> int:
    """A run whose generation 0 was committed with `stats`."""
    run_id = driven(db)
    keep(db, run_id, 0, members())
    commit = GenerationCommit(
        stats, {"seed": 1}, best=(0.5, 0), members=[(1, i, m) for i, m in enumerate(members("n"))]
    )
    store.driving.commit_generation(db, run_id, OWNER, commit)
    return run_id


def test_a_commit_writes_the_normalised_hypervolume_and_the_curve_reads_it(db: Database) -> None:
    run_id = committed(db, {**STATS, **PARETO})
    (row,) = store.curve(db, run_id)
    assert {key: row[key] for key in PARETO} == PARETO  # every digit, on both databases
    assert {key: history(db, run_id)[0][key] for key in PARETO} == PARETO
    downgrade(db, "0006")  # the release before drops the column and keeps the rest
    db.upgrade()
    rest = {key: value for key, value in row.items() if key != "normalised_hypervolume"}
    assert store.curve(db, run_id) == [rest]


def test_a_generation_before_the_column_reads_without_it_both_ways(db: Database) -> None:
    old = {key: PARETO[key] for key in ("hypervolume", "front_size")}
    run_id = committed(db, {**STATS, **old})
    before = store.curve(db, run_id)
    assert "normalised_hypervolume" not in before[0] and before[0]["hypervolume"] == 37.5
    assert "normalised_hypervolume" not in history(db, run_id)[0]
    downgrade(db, "0006")  # the release before: no such column
    db.upgrade()
    assert store.curve(db, run_id) == before  # every other column as it was


def test_a_config_stored_before_ideals_loads_with_the_defaults(db: Database) -> None:
    run_id = driven(db)
    config = resolve({**REQUEST, "objectives": ["speed", "-cost_of_transport"]})
    stored = config.to_json()
    stored["objectives"] = [
        {key: value for key, value in item.items() if key != "ideal"}
        for item in stored["objectives"]
    ]
    with db.write_session() as session:
        session.execute(update(RunRow).where(RunRow.id == run_id).values(config=stored))
    loaded = RunConfig.model_validate(store.get_run(db, run_id).config)
    assert [spec.ideal for spec in loaded.objectives] == [
        MEASURES["speed"][3],
        MEASURES["cost_of_transport"][3],
    ]
    assert loaded == config  # what a new run of the same request stores
