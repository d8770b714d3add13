"""The `simple` worker's hard time limit (`softevo.worker.watchdog`): a job that RQ's alarm
cannot interrupt (a numba loop; here a sleep with SIGALRM blocked) is given up past its limit,
said on its batch's result list, marked failed, and the same worker process goes on with the
next job."""

from __future__ import annotations

import json

import pytest
from rq import Queue
from rq.job import Job, JobStatus

from softevo.worker.queue import QUEUE, SERIALIZER, connect, engine_fingerprint, result_key
from softevo.worker.watchdog import MAX_GRACE, hard_limit

pytestmark = pytest.mark.redis
STUCK = "tests.worker.poison_job.stuck"


def test_the_hard_limit_is_the_timeout_and_as_much_again_at_most_a_minute() -> None:
    assert hard_limit(1) == 2.0
    assert hard_limit(600) == 600 + MAX_GRACE
    assert hard_limit(-1) is None and hard_limit(None) is None


def test_a_stuck_job_fails_alone_and_the_simple_worker_goes_on(redis_server, workers) -> None:
    connection = connect(redis_server.url)
    queue = Queue(QUEUE, connection=connection, serializer=SERIALIZER)
    meta = {"engine": engine_fingerprint()}
    process = workers.start("w", "--worker-class", "simple", f"--allow-function={STUCK}")
    workers.wait_ready("w")
    try:
        queue.enqueue(
            STUCK, args=("hung", [{"sleep": 30}] * 2), job_id="hung", job_timeout=1, meta=meta
        )
        _, raw = connection.blpop([result_key("hung")], timeout=20)
        payload = json.loads(raw)
        assert "hard limit of 2 s" in payload["error"] and payload["robots"] == 2
        job = Job.fetch("hung", connection=connection, serializer=SERIALIZER)
        assert job.get_status() == JobStatus.FAILED
        queue.enqueue(STUCK, args=("next", [{"sleep": 0}]), job_id="next", job_timeout=1, meta=meta)
        item = connection.blpop([result_key("next")], timeout=60)  # after a restart's warm-up
        assert item is not None and json.loads(item[1])["fitness"] == [1.0]
        assert process.poll() is None  # the same process (os.execv), still working
        assert workers.log("w").count("taking jobs") == 2
    finally:
        connection.close()
