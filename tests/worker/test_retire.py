"""Settling a batch costs no Redis round trip for its winning attempt: `RQEvaluator._retire`
fetches only the other attempts, and still takes a queued one off Redis (bench/scaling.py found
the winner's fetch, an HGETALL of the job with its robot files, at 14 % of the API process's
CPU under yappi)."""

from __future__ import annotations

import pytest
from redis import Redis
from rq.job import Job

from softevo.worker.evaluator import RQEvaluator, work_units
from softevo.worker.queue import SERIALIZER, connect

pytestmark = pytest.mark.redis

FILES = [{"voxels": ["hard", "empty", "sine"], "sim": {"duration": 1.0, "dt": 0.001}}]


def fetched(connection: Redis) -> int:
    """HGETALLs (RQ's `Job.fetch`) run since the last reset."""
    stats = connection.info("commandstats")
    return int(stats.get("cmdstat_hgetall", {}).get("calls", 0))


def test_only_the_attempts_that_lost_are_fetched(redis_server) -> None:
    evaluator = RQEvaluator(redis_server.url)
    connection = connect(redis_server.url)
    try:
        for attempt in (1, 2):  # attempt 1 queued and never taken; attempt 2 won
            evaluator._enqueue(FILES, "two", attempt)
        evaluator._enqueue(FILES, "one", 1)  # won by its first attempt
        connection.config_resetstat()
        evaluator._retire("one", 1, set(), "softevo-one-a1")
        assert fetched(connection) == 0
        evaluator._retire("two", 2, set(), "softevo-two-a2")
        assert fetched(connection) == 1  # attempt 1 only
        assert not Job.exists("softevo-two-a1", connection=connection)  # queued: taken off
        job = Job.fetch("softevo-two-a2", connection=connection, serializer=SERIALIZER)
        assert job.id == "softevo-two-a2"  # the winner is left alone
        connection.config_resetstat()
        evaluator._retire("one", 1, set(), None)  # no winner known (a timeout): fetched
        assert fetched(connection) == 1
    finally:
        evaluator.close()
        connection.close()


def test_work_units_count_occupied_voxels() -> None:
    assert work_units(FILES[0]) == pytest.approx(1000 * 2)
    assert work_units({"voxels": ("soft", "empty"), "sim": {}}) == pytest.approx(20000)
    assert work_units({"voxels": [], "springs": [[0, 1]] * 56, "sim": {}}) == pytest.approx(40000)
    assert work_units({"voxels": 3}) == 1.0  # malformed: one unit, never an error


def test_a_job_is_described_by_its_batch_not_its_robot_files(redis_server) -> None:
    """RQ would describe a job by the repr of its arguments (every robot file): costly to build
    on each enqueue and unreadable in rq-dashboard; the batch's key and size are said instead,
    and the job still carries the files and its timeout."""
    evaluator = RQEvaluator(redis_server.url)
    connection = connect(redis_server.url)
    try:
        evaluator._enqueue(FILES * 2, "described", 1)
        job = Job.fetch("softevo-described-a1", connection=connection, serializer=SERIALIZER)
        assert job.description == "softevo evaluate_batch described (2)"
        assert job.args == ["described", FILES * 2]
        assert job.timeout == 600  # nothing measured yet: the first job's hard limit
        job.delete()
    finally:
        evaluator.close()
        connection.close()
