"""Reads of a large run read only the columns they show: the individuals' listing and the
population figure never select a genome (tens of kB of JSON each), and the figure's two columns
come back as arrays, in order, a failed or pending robot's fitness NaN."""

from __future__ import annotations

import json
import re
from datetime import UTC, datetime
from typing import Any

import numpy as np
from fastapi.testclient import TestClient
from sqlalchemy import event, insert

from softevo.api import store
from softevo.api.db import Database
from softevo.api.models import IndividualRow
from softevo.core.config import RunConfig

GENOME = re.compile(r"individuals\.genome\b(?!_)")  # the column, not genome_hash
POPULATION = 4


def fill(db: Database, generations: int = 3) -> tuple[int, list[float | None]]:
    """A run of `generations` x POPULATION individuals written directly (no simulation); its
    id and fitness in order, None for the failed ones."""
    config = RunConfig.model_validate(
        {"preset": "quick", "seed": 1, "population": POPULATION, "generations": generations}
    )
    run = store.create_run(db, config)
    genome = json.loads(config.make_encoding().random(np.random.default_rng(1)).canonical)
    fitness = [None if n % 5 == 3 else 0.01 * n for n in range(generations * POPULATION)]
    with db.write_session() as session:
        session.execute(
            insert(IndividualRow),
            [
                {
                    "run_id": run.id,
                    "generation": n // POPULATION,
                    "index": n % POPULATION,
                    "genome": genome,
                    "genome_hash": f"{n:016d}",
                    "operator": "mutation",
                    "parents": [],
                    "status": "failed" if value is None else "evaluated",
                    "fitness": value,
                    "evaluated_at": datetime.now(UTC),
                }
                for n, value in enumerate(fitness)
            ],
        )
    return run.id, fitness


def test_population_reads_two_columns_in_order(db: Database) -> None:
    run_id, fitness = fill(db)
    generations, values = store.population_points(db, run_id)
    assert generations.tolist() == [n // POPULATION for n in range(len(fitness))]
    expected = np.array([np.nan if v is None else v for v in fitness])
    np.testing.assert_array_equal(values, expected)
    assert store.population_points(db, run_id + 1)[0].size == 0


def test_listings_and_the_figure_never_select_a_genome(client: TestClient) -> None:
    db: Database = client.app.state.db  # type: ignore[attr-defined]
    run_id, fitness = fill(db)
    statements: list[str] = []

    def seen(_conn: Any, _cursor: Any, statement: str, *_args: Any) -> None:
        statements.append(statement)

    event.listen(db.engine, "before_cursor_execute", seen)
    try:
        page = client.get(f"/runs/{run_id}/individuals", params={"limit": 5, "offset": 2}).json()
        one = client.get(f"/runs/{run_id}/individuals", params={"generation": 1}).json()
        figure = client.get(f"/runs/{run_id}/figures/population.png")
    finally:
        event.remove(db.engine, "before_cursor_execute", seen)
    assert page["total"] == len(fitness) and [i["id"] for i in page["items"]] == [2, 3, 4, 5, 6]
    assert [i["fitness"] for i in page["items"]] == fitness[2:7]
    assert one["total"] == POPULATION and [i["generation"] for i in one["items"]] == [1] * 4
    assert figure.status_code == 200 and figure.content.startswith(b"\x89PNG")
    selects = [s for s in statements if s.lstrip().upper().startswith("SELECT")]
    assert selects and not [s for s in selects if GENOME.search(s)]
    detail = client.get(f"/runs/{run_id}/individuals/5").json()  # the one read that needs it
    assert detail["genome"]["discrete"]
