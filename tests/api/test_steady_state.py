"""A steady-state run through the service: births are kept as they are bred, their fitness as it
lands, and a coordinator that takes the run over goes on with the same births to the in-process
curve; on RQ workers too."""

from __future__ import annotations

import pytest
from sqlalchemy import func, select

from softevo.api import store
from softevo.api.coordinator import Coordinator
from softevo.api.db import Database
from softevo.api.models import IndividualRow
from softevo.core.config import resolve
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.evolution import Evolution
from softevo.worker.evaluator import RQEvaluator
from tests.api.test_coordinator import FreezingEvaluator, drive, wait_status
from tests.reference import undisturbed

REQUEST = {
    "preset": "quick",
    "seed": 6,
    "population": 8,
    "generations": 4,
    "algorithm": "steady-state",
    "options": {"window": 6},
}


def _rows(db: Database, run_id: int) -> dict[str, int]:
    with db.read_session() as session:
        counts = session.execute(
            select(IndividualRow.status, func.count())
            .where(IndividualRow.run_id == run_id)
            .group_by(IndividualRow.status)
        ).all()
    return dict(counts)  # type: ignore[arg-type]


@pytest.mark.parametrize("window", [6, 20])  # 20: births bred up to 2.5 rows ahead
def test_the_service_gives_the_in_process_curve(db: Database, window: int) -> None:
    request = {**REQUEST, "options": {"window": window}}
    run = store.create_run(db, resolve(request))
    assert drive(db, run.id, SerialEvaluator(), batch_size=2) == "completed"
    expected = undisturbed(request).curve()
    assert store.curve(db, run.id) == expected
    rows = _rows(db, run.id)
    assert "pending" not in rows and sum(rows.values()) == 8 * 4  # every birth, none past the end
    assert rows.get("cached", 0) == sum(row["saved"] for row in expected)


@pytest.mark.parametrize("window", [6, 20])
def test_a_takeover_goes_on_with_the_same_births(db: Database, window: int) -> None:
    request = {**REQUEST, "options": {"window": window}}
    run = store.create_run(db, resolve(request))
    frozen = FreezingEvaluator(calls=7)  # frozen in row 1, with births of row 1 and 2 out
    first = Coordinator(
        db, frozen, batch_size=2, lease_seconds=1.0, poll_seconds=0.05, save_seconds=0
    )
    first.start()
    frozen.wait_frozen()
    first.stopping.set()  # stops heartbeating, as if SIGSTOPped
    kept = _rows(db, run.id)
    assert kept.get("evaluated", 0) >= 8  # the births that landed were written as they landed
    second = Coordinator(db, SerialEvaluator(), batch_size=2, lease_seconds=1.0, poll_seconds=0.05)
    second.start()
    try:
        assert wait_status(db, run.id, ("completed", "failed")) == "completed"
        frozen.release.set()  # its late batches must not write a second fitness
    finally:
        second.stop()
        first.stop()
    record = store.get_run(db, run.id)
    assert record.takeovers >= 1 and record.error is None
    assert store.curve(db, run.id) == undisturbed(request).curve()
    rows = _rows(db, run.id)
    assert "pending" not in rows and sum(rows.values()) == 8 * 4


@pytest.mark.redis
def test_two_rq_workers_give_the_serial_run(redis_server, workers) -> None:  # type: ignore[no-untyped-def]
    for name in ("left", "right"):
        workers.start(name)
    for name in ("left", "right"):
        workers.wait_ready(name)
    on_rq = Evolution.start(resolve(REQUEST))
    evaluator = RQEvaluator(redis_server.url)
    try:
        on_rq.run(evaluator)
    finally:
        evaluator.close()
    assert on_rq.curve() == undisturbed(REQUEST).curve()
    assert on_rq.state.to_json() == undisturbed(REQUEST).state.to_json()
