"""The coordinator and its storage on SQLite and PostgreSQL: the schema, exactly-once fitness,
leases, and a takeover after a coordinator stops answering that ends with the undisturbed curve.
(The same curve as `softevo run` is checked through the API in `test_api.py`.)"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from sqlalchemy import event, func, select
from sqlalchemy.exc import IntegrityError

from softevo.api import store
from softevo.api.coordinator import Coordinator
from softevo.api.db import Database
from softevo.api.models import Base, IndividualRow
from softevo.api.store import front as front_store
from softevo.core.config import resolve
from softevo.core.evaluator import BatchResult
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.stream import Flights
from tests.reference import front_points, undisturbed

REQUEST = {"preset": "quick", "seed": 5, "population": 8, "generations": 4}


def wait_status(db: Database, run_id: int, statuses: tuple[str, ...], timeout: float = 60) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        status = store.get_run(db, run_id).status
        if status in statuses:
            return status
        time.sleep(0.05)
    raise AssertionError(f"run {run_id} is still {status}")


def drive(db: Database, run_id: int, evaluator: SerialEvaluator, **options: Any) -> str:
    """Run a coordinator until `run_id` stops; its final status."""
    coordinator = Coordinator(db, evaluator, poll_seconds=0.05, **options)
    coordinator.start()
    try:
        return wait_status(db, run_id, ("completed", "failed"))
    finally:
        coordinator.stop()


def test_migrations_create_exactly_the_models_schema(db: Database) -> None:
    with db.engine.connect() as connection:
        differences = compare_metadata(MigrationContext.configure(connection), Base.metadata)
    assert differences == []


def test_a_second_row_for_an_individual_is_impossible(db: Database) -> None:
    run = store.create_run(db, resolve(REQUEST))
    row = {
        "run_id": run.id,
        "generation": 0,
        "index": 0,
        "genome": {},
        "genome_hash": "h",
        "operator": "random",
        "parents": [],
        "status": "pending",
    }
    with db.write_session() as session:
        session.add(IndividualRow(**row))
    with pytest.raises(IntegrityError), db.write_session() as session:
        session.add(IndividualRow(**row))


def test_lease_is_exclusive_until_it_expires(db: Database) -> None:
    run = store.create_run(db, resolve(REQUEST))
    assert store.leases.candidates(db, 10) == [run.id]
    assert store.leases.acquire(db, run.id, "a", 0.5)
    assert not store.leases.acquire(db, run.id, "b", 0.5)
    assert store.leases.candidates(db, 10) == []
    assert store.leases.renew(db, run.id, "a", 0.5)
    later = time.time() + 0.6  # a clock past the lease's end, not a sleep
    assert store.leases.candidates(db, 10, at=later) == [run.id]
    assert store.leases.acquire(db, run.id, "b", 5, at=later)
    assert not store.leases.renew(db, run.id, "a", 5)  # the old owner is fenced off
    record = store.get_run(db, run.id)
    assert record.status == "running" and record.takeovers == 1


class FreezingEvaluator(SerialEvaluator):
    """Evaluates `calls` batches, then hangs like a stopped process until released."""

    def __init__(self, calls: int) -> None:
        super().__init__()
        self.calls = calls
        self.release = threading.Event()

    def evaluate_batch(
        self, robot_files: Sequence[dict[str, Any]], key: str | None = None
    ) -> BatchResult:
        self.calls -= 1
        if self.calls < 0:
            self.release.wait(60)
        return super().evaluate_batch(robot_files, key)

    def wait_frozen(self, timeout: float = 60) -> None:
        """Until its `calls` batches are done and the next one hangs."""
        deadline = time.monotonic() + timeout
        while self.calls >= 0:
            assert time.monotonic() < deadline, "the evaluator never froze"
            time.sleep(0.02)


#: NSGA-II and AFPO with objectives: the taken-over run must also rebuild what they breed from
#: (objective values, births, lineages) and the front so far from the database.
PARETO = {"objectives": ["speed", "-cost_of_transport"], "options": {"variation": "explore"}}


@pytest.mark.parametrize(
    "request_body",
    [
        REQUEST,
        {**REQUEST, "algorithm": "nsga2", **PARETO},
        {**REQUEST, "algorithm": "afpo", **PARETO},
    ],
    ids=["ga", "nsga2", "afpo"],
)
def test_takeover_after_a_coordinator_freezes_gives_the_undisturbed_curve(
    db: Database, request_body: dict[str, Any]
) -> None:
    run = store.create_run(db, resolve(request_body))
    frozen = FreezingEvaluator(calls=5)
    first = Coordinator(db, frozen, batch_size=2, lease_seconds=1.0, poll_seconds=0.05)
    first.start()
    frozen.wait_frozen()
    first.stopping.set()  # the frozen coordinator stops heartbeating, as if SIGSTOPped
    second = Coordinator(db, SerialEvaluator(), batch_size=2, lease_seconds=1.0, poll_seconds=0.05)
    second.start()
    try:
        assert wait_status(db, run.id, ("completed", "failed")) == "completed"
        frozen.release.set()  # its late batch must not write a second fitness
    finally:
        second.stop()
        first.stop()
    record = store.get_run(db, run.id)
    assert record.takeovers >= 1 and record.error is None
    with db.read_session() as session:
        statuses = session.execute(
            select(IndividualRow.status, func.count())
            .where(IndividualRow.run_id == run.id)
            .group_by(IndividualRow.status)
        ).all()
    assert "pending" not in dict(statuses)
    assert sum(count for _, count in statuses) == 8 * 4
    reference = undisturbed(request_body)
    assert store.curve(db, run.id) == reference.curve()
    if "objectives" in request_body:  # and the front is the undisturbed run's
        front = front_points(request_body, front_store.evaluated(db, run.id))
        assert front == reference.state.data["front"] and front


def test_a_failing_evaluator_fails_the_run_with_its_reason(db: Database) -> None:
    class Broken(SerialEvaluator):
        def evaluate_batch(
            self, robot_files: Sequence[dict[str, Any]], key: str | None = None
        ) -> BatchResult:
            raise RuntimeError("worker pool is gone")

    run = store.create_run(db, resolve(REQUEST))
    assert drive(db, run.id, Broken()) == "failed"
    assert "worker pool is gone" in (store.get_run(db, run.id).error or "")


def test_failed_robots_are_nan_ranked_last_not_zero(db: Database) -> None:
    class HalfFailing(SerialEvaluator):
        def evaluate_batch(
            self, robot_files: Sequence[dict[str, Any]], key: str | None = None
        ) -> BatchResult:
            result = super().evaluate_batch(robot_files, key)
            values = result.fitness.copy()
            values[::2] = np.nan
            return BatchResult(values, result.worker, result.seconds)

    run = store.create_run(db, resolve(REQUEST))
    assert drive(db, run.id, HalfFailing(), batch_size=8) == "completed"
    first = store.curve(db, run.id)[0]
    assert first["failed"] == 4 and first["min"] is not None and first["min"] > -1
    items, _ = store.list_individuals(db, store.get_run(db, run.id), 0, 0, 100)
    failed = [item for item in items if item["status"] == "failed"]
    assert len(failed) == 4 and all(item["fitness"] is None for item in failed)


class Counting(SerialEvaluator):
    """Counts the robots and batches it evaluates."""

    def __init__(self) -> None:
        super().__init__()
        self.batches = self.robots = 0

    def evaluate_batch(
        self, robot_files: Sequence[dict[str, Any]], key: str | None = None
    ) -> BatchResult:
        self.batches += 1
        self.robots += len(robot_files)
        return super().evaluate_batch(robot_files, key)


def count_writes(db: Database) -> list[int]:
    """A one-item list that counts the write transactions begun on `db` from now on."""
    writes = [0]

    @event.listens_for(db.engine, "begin")
    def _begin(connection: Any) -> None:
        writes[0] += connection.get_execution_options().get("softevo_write", False)

    return writes


@pytest.mark.parametrize("save_seconds", [60.0, 0.0])
def test_quick_batches_cost_one_write_per_generation(db: Database, save_seconds: float) -> None:
    """Batches landing within `save_seconds` of the run's last write wait for the generation's
    commit, which also keeps the next generation's births (the first one's go with the run's
    first write): one write transaction a generation. With 0, each batch is saved as it lands.
    The curve is the same either way."""
    run = store.create_run(db, resolve(REQUEST))
    evaluator = Counting()
    writes = count_writes(db)
    options = {"batch_size": 2, "save_seconds": save_seconds, "lease_seconds": 120.0}
    assert drive(db, run.id, evaluator, **options) == "completed"
    generations = REQUEST["generations"]
    # taking the run, one commit a generation, and the stop's release; with 0, also each batch
    # and the first generation's births, written at once
    expected = 1 + generations + 1 + (1 + evaluator.batches if save_seconds == 0 else 0)
    assert writes[0] == expected, (writes[0], evaluator.batches)
    assert evaluator.batches > generations  # several batches a generation were coalesced
    assert store.curve(db, run.id) == undisturbed(REQUEST).curve()


def test_fitness_waiting_for_its_write_is_saved_at_a_shutdown(
    db: Database, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Three batches of generation 0 land and wait (a minute's `save_seconds`), the fourth hangs;
    a clean shutdown saves the three, and the successor evaluates only the rest."""
    landings, evaluate = threading.Semaphore(0), Flights._evaluate

    def evaluate_and_count(self: Flights, births: Any, files: Any, key: str) -> None:
        evaluate(self, births, files, key)
        landings.release()

    monkeypatch.setattr(Flights, "_evaluate", evaluate_and_count)
    run = store.create_run(db, resolve(REQUEST))
    frozen = FreezingEvaluator(calls=3)
    first = Coordinator(db, frozen, batch_size=2, save_seconds=60.0, poll_seconds=0.05)
    first.start()
    frozen.wait_frozen()
    assert all(landings.acquire(timeout=10) for _ in range(3))  # landed in the step, unsaved
    first.stop()
    frozen.release.set()
    with db.read_session() as session:
        saved = session.scalar(
            select(func.count()).where(
                IndividualRow.run_id == run.id,
                IndividualRow.generation == 0,
                IndividualRow.status.in_(("evaluated", "failed")),
            )
        )
    assert saved == 6
    successor = Counting()
    assert drive(db, run.id, successor, batch_size=2) == "completed"
    record = store.get_run(db, run.id)
    assert store.curve(db, run.id) == undisturbed(REQUEST).curve()
    assert successor.robots == record.evaluations - 6


class Dropping(FreezingEvaluator):
    """Hangs after `calls` batches and records what it is asked to drop (then releases)."""

    def __init__(self, calls: int) -> None:
        super().__init__(calls)
        self.dropped: list[str] = []

    def drop(self, key_prefix: str) -> None:
        self.dropped.append(key_prefix)
        self.release.set()


@pytest.mark.parametrize("where", ["this coordinator", "another API process"])
def test_a_cancel_drops_the_runs_batches_still_out(db: Database, where: str) -> None:
    """Cancelled through this coordinator, or in the database by another API process (the lease
    fence stops the driver at its next heartbeat): the evaluator is told to give up the run's
    batches (`run<id>-`)."""
    run = store.create_run(db, resolve(REQUEST))
    evaluator = Dropping(calls=2)
    coordinator = Coordinator(db, evaluator, batch_size=2, lease_seconds=0.6, poll_seconds=0.05)
    coordinator.start()
    try:
        evaluator.wait_frozen()
        store.cancel_run(db, run.id)
        if where == "this coordinator":
            coordinator.cancel(run.id)
        assert coordinator.join(run.id, timeout=30)
    finally:
        evaluator.release.set()
        coordinator.stop()
    assert evaluator.dropped == [f"run{run.id}-"]
    assert store.get_run(db, run.id).status == "cancelled"


#: For what does not depend on which database it is: the `db` fixture on SQLite only.
ON_SQLITE = pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)


@ON_SQLITE
def test_an_idle_scheduler_backs_off_but_never_past_a_heartbeat(db: Database) -> None:
    """While its looks find no run, the pause doubles up to 8 polls; a heartbeat due sooner
    shortens it; one overdue (the database away) is retried at the poll, not in a busy loop."""
    now = time.monotonic()
    coordinator = Coordinator(db, SerialEvaluator(), poll_seconds=0.5, lease_seconds=15.0)
    assert [coordinator._pause(quiet, now) for quiet in (0, 1, 2, 3, 4, 8)] == pytest.approx(
        [0.5, 1.0, 2.0, 4.0, 4.0, 4.0]
    )
    short = Coordinator(db, SerialEvaluator(), poll_seconds=0.5, lease_seconds=3.0)
    assert 0.9 <= short._pause(3, now) <= 1.0  # the heartbeat, every second, comes first
    assert short._pause(3, now - 100) == 0.5  # overdue: try again at the poll
    assert coordinator._pause(0, now - 100) == 0.5


@ON_SQLITE
def test_an_idle_scheduler_looks_less_often_and_a_queued_run_wakes_it(db: Database) -> None:
    coordinator = Coordinator(db, SerialEvaluator(), poll_seconds=0.05, lease_seconds=30.0)
    coordinator.start()
    try:
        assert coordinator.wait_ticks(5, 30)  # pauses of 0.05, 0.1, 0.2, 0.4, 0.4 s
        looked = time.monotonic()
        assert coordinator.wait_ticks(2, 30)
        assert time.monotonic() - looked >= 0.35  # not 2 x 0.05 s: 0.4 s apart by now
        run = store.create_run(db, resolve({**REQUEST, "generations": 1}))
        coordinator.wake()  # what POST /runs does
        assert wait_status(db, run.id, ("completed",), timeout=60) == "completed"
    finally:
        coordinator.stop()
