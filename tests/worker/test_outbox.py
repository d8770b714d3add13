"""Jobs that batch threads enqueue at the same time reach Redis together (`worker/outbox.py`):
every job arrives whole, in fewer round trips than jobs, and a failed send fails each job it
held, so each thread enqueues again as it does when Redis is away."""

from __future__ import annotations

import threading

import pytest
from redis.exceptions import ConnectionError as RedisConnectionError
from rq import Queue
from rq.job import Job

from softevo.worker.evaluator import RQEvaluator
from softevo.worker.queue import SERIALIZER, connect

pytestmark = pytest.mark.redis

FILES = [{"voxels": ["hard", "empty", "sine"], "sim": {"duration": 1.0, "dt": 0.001}}]


def enqueue_together(evaluator: RQEvaluator, keys: list[str]) -> list[BaseException]:
    """`keys` enqueued by as many threads released at once; what they raised."""
    start, raised = threading.Barrier(len(keys)), []

    def one(key: str) -> None:
        start.wait()
        try:
            evaluator._enqueue(FILES, key, 1)
        except BaseException as error:  # each thread's, read by the test
            raised.append(error)

    threads = [threading.Thread(target=one, args=(key,)) for key in keys]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(30)
    return raised


def test_jobs_enqueued_together_arrive_whole_in_fewer_round_trips(redis_server) -> None:
    evaluator = RQEvaluator(redis_server.url, queue="outbox-test")
    connection = connect(redis_server.url)
    keys = [f"together-{i}" for i in range(24)]
    try:
        connection.client_pause(500, all=False)  # writes wait: the first send holds the door
        assert enqueue_together(evaluator, keys) == []
        queue = Queue("outbox-test", connection=connection, serializer=SERIALIZER)
        assert sorted(queue.job_ids) == sorted(f"softevo-{key}-a1" for key in keys)
        for key in keys:
            job = Job.fetch(f"softevo-{key}-a1", connection=connection, serializer=SERIALIZER)
            assert job.args == [key, FILES] and job.meta["engine"] == evaluator.engine
        outbox = evaluator.outbox
        assert outbox.jobs == len(keys)
        assert outbox.sends <= len(keys) // 4  # the others' jobs gathered behind the first
    finally:
        evaluator.close()
        connection.close()


def test_the_same_job_asked_twice_in_one_send_is_sent_once(redis_server) -> None:
    """Two GETs of one replay ask for the same job id at once: RQ's `enqueue_many` refuses a
    repeated id, so the outbox keeps one and both callers are answered."""
    evaluator = RQEvaluator(redis_server.url, queue="outbox-twice")
    connection = connect(redis_server.url)
    try:
        assert enqueue_together(evaluator, ["same"] * 6) == []
        queue = Queue("outbox-twice", connection=connection, serializer=SERIALIZER)
        assert "softevo-same-a1" in queue.job_ids
        assert Job.exists("softevo-same-a1", connection=connection)
    finally:
        evaluator.close()
        connection.close()


def test_a_failed_send_fails_every_job_it_held_and_the_next_send_goes(redis_server) -> None:
    """Redis killed: every thread's enqueue raises Redis's error (none hangs, none is lost
    silently); Redis back: the same outbox sends again."""
    evaluator = RQEvaluator(redis_server.url, queue="outbox-down")
    keys = [f"down-{i}" for i in range(8)]
    try:
        redis_server.kill()
        raised = enqueue_together(evaluator, keys)
        assert len(raised) == len(keys)
        assert all(isinstance(error, RedisConnectionError | OSError) for error in raised)
        redis_server.start()
        assert enqueue_together(evaluator, keys) == []
        connection = connect(redis_server.url)
        queue = Queue("outbox-down", connection=connection, serializer=SERIALIZER)
        assert sorted(queue.job_ids) == sorted(f"softevo-{key}-a1" for key in keys)
        connection.close()
    finally:
        evaluator.close()


def test_redis_py_packs_and_parses_in_c() -> None:
    """hiredis (the `redis[hiredis]` extra, in the locks) is what redis-py packs commands and
    parses replies with: about a fifth of an enqueue's CPU (BENCHMARKS.md, issue 52)."""
    from redis.utils import HIREDIS_AVAILABLE

    assert HIREDIS_AVAILABLE
