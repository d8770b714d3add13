"""Each individual's record of measures in the store (revision 0004), on SQLite and PostgreSQL:
written with the fitness to the last bit, read back by what a successor reads; and a database of
the release before (revision 0003: a `heading` column, no records) upgraded with its values
intact, read, taken over and finished with the undisturbed curve and archive, and downgraded."""

from __future__ import annotations

import json
import math
import threading
from typing import Any

import pytest
from alembic import command
from sqlalchemy import text

from softevo.api import store
from softevo.api.coordinator import Coordinator
from softevo.api.db import Database, alembic_config
from softevo.api.store.driving import GenerationCommit
from softevo.api.store.fitness_rows import Landed, measures_text
from softevo.core.config import resolve
from softevo.core.evaluator import BatchResult
from softevo.core.nulls import Record, from_null_record
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.configured import StrategyState
from tests.api.store.test_store import OWNER, STATS, driven, keep, members
from tests.api.test_coordinator import wait_status
from tests.reference import undisturbed

#: a heading whose last bits a float32 or a decimal round trip would lose
EXACT = math.degrees(math.atan2(0.1, -0.3))
RECORD = {"speed": 0.1 + 0.2, "heading": EXACT, "energy": math.nan, "stable": 1.0}


def same(found: dict[str, float], expected: dict[str, float]) -> bool:
    """The same names and, to the bit, the same values (NaN for NaN)."""
    return found.keys() == expected.keys() and all(
        found[name].hex() == expected[name].hex() for name in expected
    )


def test_a_record_is_written_with_its_fitness_and_read_back_to_the_bit(db: Database) -> None:
    run_id = driven(db)
    keep(db, run_id, 0, members())
    landed = [Landed({0: 0.5, 1: math.nan}, "w1", 0.1, {0: RECORD, 1: {"stable": 0.0}})]
    store.driving.save_fitness(db, run_id, OWNER, 0, landed)
    found = store.births.stored_births(db, run_id, 0)  # what a successor reads back
    assert found[(0, 0)][1] == 0.5 and math.isnan(found[(0, 1)][1]) and found[(0, 2)][1] is None
    assert same(found[(0, 0)][2], RECORD) and found[(0, 1)][2] == {"stable": 0.0}
    store.driving.commit_generation(
        db,
        run_id,
        OWNER,
        GenerationCommit(
            STATS,
            {"seed": 1},
            cached={3: 0.5},
            cached_measures={3: RECORD},
            landed=[Landed({2: 0.25}, "w2", 0.1)],
            best=(0.5, 0),
            members=[(1, i, m) for i, m in enumerate(members("n"))],
        ),
    )
    fitness, measures = store.driving.known_fitness(db, run_id, 1)
    assert fitness == {"x0": 0.5, "x1": fitness["x1"], "x2": 0.25, "x3": 0.5}
    assert same(measures["x0"], RECORD) and same(measures["x3"], RECORD)
    assert measures["x2"] == {}  # landed without a record
    items, _ = store.list_individuals(db, store.get_run(db, run_id), 0, 0, 10)
    assert items[0]["measures"] == {**RECORD, "energy": None} and items[2]["measures"] == {}


def test_a_record_is_stored_as_json_with_every_value_that_is_not_a_number_null() -> None:
    text = measures_text(
        {"speed": 0.1, "energy": math.nan, "efficiency": math.inf, "cost_of_transport": -math.inf}
    )
    assert json.loads(text) == {
        "speed": 0.1,
        "energy": None,
        "efficiency": None,
        "cost_of_transport": None,
    }
    assert json.loads(measures_text({"speed": 0.1, "energy": math.nan})) == {
        "speed": 0.1,
        "energy": None,
    }
    assert measures_text({}) == measures_text(None) == "{}"


def test_a_record_read_from_json_is_encoded_once_and_as_a_plain_one() -> None:
    """A cached genome's record is written again every generation: its text is made once."""
    record = from_null_record({"speed": 0.1 + 0.2, "energy": None, "heading": EXACT})
    assert isinstance(record, Record)
    text = measures_text(record)
    assert text == measures_text(dict(record)) and json.loads(text)["energy"] is None
    assert record.text == text  # kept, not made again the next generation it is written
    infinite = from_null_record({"efficiency": math.inf})
    assert measures_text(infinite) == '{"efficiency":null}' == measures_text(infinite)


def at_revision_0003(db: Database, objective: str) -> int:
    """A run of the release before, at revision 0003: four individuals of generation 0 as it
    stored them (evaluated, failed, cached, pending), each fitness and heading in a column."""
    db.upgrade("0003")
    config = resolve({"preset": "quick", "population": 4, "objective": objective})
    run = store.create_run(db, config)
    rows = [
        ("evaluated", 0.125, EXACT),
        ("failed", None, None),
        ("cached", 0.125, EXACT),
        ("pending", None, None),
    ]
    with db.engine.begin() as connection:
        for index, (status, fitness, heading) in enumerate(rows):
            connection.execute(
                text(
                    'INSERT INTO individuals (run_id, generation, "index", genome, genome_hash, '
                    "operator, parents, status, fitness, heading) VALUES (:run, 0, :index, '{}', "
                    ":hash, 'random', '[]', :status, :fitness, :heading)"
                ),
                {
                    "run": run.id,
                    "index": index,
                    "hash": f"x{index}",
                    "status": status,
                    "fitness": fitness,
                    "heading": heading,
                },
            )
    return run.id


@pytest.mark.empty_database
@pytest.mark.parametrize("objective", ["speed", "forward"])
def test_a_database_of_revision_0003_upgrades_with_its_values_intact(
    database_url: str, objective: str
) -> None:
    db = Database(database_url)
    try:
        run_id = at_revision_0003(db, objective)
        db.upgrade()
        name = {"speed": "speed", "forward": "forward_speed"}[objective]
        fitness, measures = store.driving.known_fitness(db, run_id, 1)
        assert fitness["x0"] == fitness["x2"] == 0.125 and math.isnan(fitness["x1"])
        assert same(measures["x0"], {name: 0.125, "heading": EXACT}) and measures["x1"] == {}
        assert "x3" not in measures  # pending: nothing measured yet
        items, total = store.list_individuals(db, store.get_run(db, run_id), 0, 0, 10)
        assert total == 4 and [item["fitness"] for item in items] == [0.125, None, 0.125, None]
        assert [item["measures"] for item in items][1:] == [
            {},
            {name: 0.125, "heading": EXACT},
            None,
        ]
        downgrade(db, "0003")
        with db.engine.connect() as connection:
            headings = connection.execute(
                text('SELECT heading FROM individuals ORDER BY "index"')
            ).scalars()
            found = [h if h is None else h.hex() for h in headings]
            assert found == [EXACT.hex(), None, EXACT.hex(), None]
    finally:
        db.dispose()


def downgrade(db: Database, revision: str) -> None:
    """The migrations undone down to `revision`, as `softevo.api.db.upgrade` applies them."""
    config = alembic_config()
    with db.engine.begin() as connection:
        config.attributes["connection"] = connection
        command.downgrade(config, revision)


QD_REQUEST = {
    "preset": "quick",
    "seed": 3,
    "population": 8,
    "generations": 4,
    "sim": {"duration": 1.0},
    "algorithm": "map-elites",
    "descriptors": ["heading", "actuated"],
    "bins": [6, 3],
}


class Stopping(SerialEvaluator):
    """Evaluates `calls` batches, then waits until released (the coordinator is stopped)."""

    def __init__(self, calls: int) -> None:
        super().__init__()
        self.calls, self.release, self.held = calls, threading.Event(), threading.Event()

    def evaluate_batch(self, robot_files: Any, key: str | None = None) -> BatchResult:
        self.calls -= 1
        if self.calls < 0:
            self.held.set()
            self.release.wait(60)
        return super().evaluate_batch(robot_files, key)


@pytest.mark.empty_database
def test_a_run_stored_at_revision_0003_is_taken_over_with_the_undisturbed_curve(
    database_url: str,
) -> None:
    """A MAP-Elites run over the measured `heading`, stopped half way, its database taken down
    to 0003 (what the release before stored: the heading alone), upgraded, and finished: the
    curve and the archive are those of the run undisturbed."""
    db = Database(database_url)
    try:
        db.upgrade()
        run = store.create_run(db, resolve(QD_REQUEST))
        stopping = Stopping(calls=6)
        first = Coordinator(db, stopping, batch_size=2, poll_seconds=0.05)
        first.start()
        assert stopping.held.wait(60)
        first.stop()
        stopping.release.set()
        done = store.get_run(db, run.id).generations_done
        assert 0 < done < QD_REQUEST["generations"]
        downgrade(db, "0003")
        db.upgrade()
        second = Coordinator(db, SerialEvaluator(), batch_size=2, poll_seconds=0.05)
        second.start()
        try:
            assert wait_status(db, run.id, ("completed", "failed")) == "completed"
        finally:
            second.stop()
        reference = undisturbed(QD_REQUEST)
        assert store.curve(db, run.id) == reference.curve()
        state = StrategyState.from_json(store.driving.load(db, run.id)[1])
        assert state.archive is not None and reference.state.archive is not None
        assert state.archive.to_json() == reference.state.archive.to_json()
    finally:
        db.dispose()
