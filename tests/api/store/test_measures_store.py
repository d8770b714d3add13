"""The measured heading in the store (revision 0003), on SQLite and PostgreSQL: written with the
fitness to the last bit, read back by what a successor reads, and NULL (NaN) for individuals
stored before the revision, which still load."""

from __future__ import annotations

import math

import pytest
from sqlalchemy import text

from softevo.api import store
from softevo.api.db import Database
from softevo.api.store.driving import GenerationCommit, Landed
from tests.api.store.test_store import OWNER, STATS, driven, members

#: a heading whose last bits a float32 or a decimal round trip would lose
EXACT = math.degrees(math.atan2(0.1, -0.3))


def test_a_heading_is_written_with_its_fitness_and_read_back_to_the_bit(db: Database) -> None:
    run_id = driven(db)
    store.driving.keep_generation(db, run_id, OWNER, 0, members())
    landed = [Landed({0: 0.5, 1: math.nan}, "w1", 0.1, {0: EXACT, 1: math.nan})]
    store.driving.save_fitness(db, run_id, OWNER, 0, landed)
    fitness, heading = store.driving.keep_generation(db, run_id, OWNER, 0, members())  # successor
    assert fitness[0] == 0.5 and math.isnan(fitness[1]) and set(fitness) == set(heading) == {0, 1}
    assert heading[0].hex() == EXACT.hex() and math.isnan(heading[1])
    store.driving.commit_generation(
        db, run_id, OWNER,
        GenerationCommit(STATS, {"seed": 1}, cached={3: 0.5}, cached_heading={3: EXACT},
                         landed=[Landed({2: 0.25}, "w2", 0.1, {2: -45.0})], best=(0.5, 0),
                         upcoming=members("n")),
    )  # fmt: skip
    fitness, heading = store.driving.known_fitness(db, run_id, 1)
    assert fitness == {"x0": 0.5, "x1": fitness["x1"], "x2": 0.25, "x3": 0.5}
    assert heading["x0"].hex() == heading["x3"].hex() == EXACT.hex() and heading["x2"] == -45.0
    assert math.isnan(heading["x1"])


@pytest.mark.empty_database
def test_individuals_stored_before_revision_0003_load_with_no_heading(database_url: str) -> None:
    """A database at 0002 with an evaluated generation, upgraded: its fitness is as it was, its
    headings are NaN (no cell for the `heading` descriptor), and the run's rows still load."""
    db = Database(database_url)
    try:
        db.upgrade("0002")
        run_id = driven(db)
        with db.engine.begin() as connection:
            for index in range(4):
                connection.execute(
                    text(
                        'INSERT INTO individuals (run_id, generation, "index", genome, '
                        "genome_hash, operator, parents, status, fitness) VALUES (:run, 0, "
                        ":index, '{}', :hash, 'random', '[]', 'evaluated', :fitness)"
                    ),
                    {"run": run_id, "index": index, "hash": f"x{index}", "fitness": index / 8},
                )
        db.upgrade()
        fitness, heading = store.driving.known_fitness(db, run_id, 1)
        assert fitness == {f"x{i}": i / 8 for i in range(4)}
        assert set(heading) == set(fitness) and all(math.isnan(h) for h in heading.values())
        known, known_heading = store.driving.keep_generation(db, run_id, OWNER, 0, members())
        assert known == {i: i / 8 for i in range(4)}
        assert all(math.isnan(h) for h in known_heading.values())
        items, total = store.list_individuals(db, store.get_run(db, run_id), 0, 0, 10)
        assert total == 4 and [item["fitness"] for item in items] == [i / 8 for i in range(4)]
    finally:
        db.dispose()
