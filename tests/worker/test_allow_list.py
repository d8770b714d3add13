"""A worker runs softevo's jobs and nothing else (`softevo.worker.allow_list`): a job written into
Redis that names another function (`os.system`, `builtins.eval`) or any callback fails, runs
nothing, is said in the worker's log, and the worker goes on to evaluate the next batch."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from rq import Queue
from rq.job import JobStatus

from softevo.core.config import resolve
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.robots.robot_file import robot_to_json
from softevo.worker.evaluator import RQEvaluator
from softevo.worker.queue import JOB_FUNCTION, QUEUE, SERIALIZER, connect
from tests.services import RedisServer, Workers


def settle(queue: Queue, job_id: str, timeout: float = 30) -> JobStatus:
    deadline = time.monotonic() + timeout
    while True:
        status = queue.fetch_job(job_id).get_status()
        if status in (JobStatus.FINISHED, JobStatus.FAILED) or time.monotonic() > deadline:
            return status
        time.sleep(0.05)


def test_a_worker_refuses_any_function_but_softevos(
    redis_server: RedisServer, workers: Workers, tmp_path: Path
) -> None:
    workers.start("guard")
    workers.wait_ready("guard")
    touched = tmp_path / "touched"
    connection = connect(redis_server.url)
    queue = Queue(QUEUE, connection=connection, serializer=SERIALIZER)
    hostile = [
        queue.enqueue("os.system", args=[f"touch {touched}"], job_id="evil-system"),
        queue.enqueue("builtins.eval", args=[f"open('{touched}', 'w')"], job_id="evil-eval"),
        # softevo's own function, but with a callback that would run anything
        queue.enqueue(
            JOB_FUNCTION, args=["cb", []], job_id="evil-callback", on_success="os.system"
        ),
    ]
    for job in hostile:
        assert settle(queue, job.id) == JobStatus.FAILED, job.id
    assert not touched.exists()
    log = workers.log("guard")
    for job in hostile:
        assert f"refused job {job.id}" in log
    assert workers.processes["guard"].poll() is None  # it goes on ...
    evolution = Evolution.start(resolve({"preset": "quick", "population": 3, "seed": 2}))
    files = [robot_to_json(evolution.robot(item)) for item in evolution.individuals()]
    with RQEvaluator(redis_server.url, poll_seconds=0.2) as evaluator:  # ... with real work
        result = evaluator.evaluate_batch(files, "after-the-refusals")
    expected = SerialEvaluator().evaluate_batch(files).fitness
    assert np.array_equal(result.fitness, expected, equal_nan=True)
    assert result.worker == "guard"
    connection.close()


def test_a_malformed_job_never_stops_a_worker(redis_server: RedisServer, workers: Workers) -> None:
    """A job hash with a garbage date is moved aside (`softevo:malformed:<id>`), one with
    garbage data fails into RQ's failed registry; the worker, and one started after them, go on
    to evaluate a real batch."""
    connection = connect(redis_server.url)
    queue_key = f"rq:queue:{QUEUE}"
    connection.sadd("rq:queues", queue_key)
    connection.hset(
        "rq:job:bad-date",
        mapping={"data": "[1,2]", "created_at": "garbage", "status": "queued", "origin": QUEUE},
    )
    connection.hset(
        "rq:job:bad-data",
        mapping={
            "data": "not json",
            "created_at": "2026-12-01T00:00:00.000000Z",
            "status": "queued",
            "origin": QUEUE,
        },
    )
    connection.rpush(queue_key, "bad-date", "bad-data")
    workers.start("first")
    workers.wait_ready("first")
    deadline = time.monotonic() + 30
    queue = Queue(QUEUE, connection=connection, serializer=SERIALIZER)
    while not (
        connection.exists("softevo:malformed:bad-date")
        and "bad-data" in queue.failed_job_registry.get_job_ids()
    ):
        assert time.monotonic() < deadline, workers.log("first")
        time.sleep(0.05)
    assert "malformed job bad-date moved aside" in workers.log("first")
    workers.start("second")  # its start-up clean-up meets whatever is left: it must not die
    workers.wait_ready("second")
    evolution = Evolution.start(resolve({"preset": "quick", "population": 3, "seed": 4}))
    files = [robot_to_json(evolution.robot(item)) for item in evolution.individuals()]
    with RQEvaluator(redis_server.url, poll_seconds=0.2) as evaluator:
        result = evaluator.evaluate_batch(files, "after-the-poison")
    expected = SerialEvaluator().evaluate_batch(files).fitness
    assert np.array_equal(result.fitness, expected, equal_nan=True)
    assert workers.processes["first"].poll() is None and workers.processes["second"].poll() is None
    connection.close()


def test_a_worker_of_another_engine_refuses_the_job_and_the_run_is_told(
    redis_server: RedisServer, workers: Workers
) -> None:
    """A job carries the sender's engine fingerprint (softevo, numpy, numba, llvmlite
    versions); a worker with another refuses it, says so in its log and on the batch's result
    list, and the sender raises, naming both, instead of mixing fitness of two engines."""
    import pytest

    from softevo.worker.evaluator import EngineMismatchError
    from softevo.worker.queue import engine_fingerprint

    workers.start("other")
    workers.wait_ready("other")
    evolution = Evolution.start(resolve({"preset": "quick", "population": 2, "seed": 5}))
    files = [robot_to_json(evolution.robot(item)) for item in evolution.individuals()]
    old = "softevo 0.0.1, numpy 1.26.0, numba 0.60.0, llvmlite 0.43.0"
    with (
        RQEvaluator(redis_server.url, poll_seconds=0.2, engine=old) as evaluator,
        pytest.raises(EngineMismatchError) as refused,
    ):
        evaluator.evaluate_batch(files, "old-engine")
    assert old in str(refused.value) and engine_fingerprint() in str(refused.value)
    assert "refused job softevo-old-engine-a1" in workers.log("other")
    with RQEvaluator(redis_server.url, poll_seconds=0.2) as evaluator:  # the same engine: fine
        result = evaluator.evaluate_batch(files, "same-engine")
    assert np.array_equal(
        result.fitness, SerialEvaluator().evaluate_batch(files).fitness, equal_nan=True
    )
    assert workers.processes["other"].poll() is None
