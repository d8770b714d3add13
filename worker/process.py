"""`softevo worker`: an RQ worker that loads (or compiles) the physics kernels before it takes
its first job, so no job pays for compilation or a cold import.

The default class is RQ's forking `Worker`: each job runs in a child forked from the warm parent
(kernels already loaded), and the parent can kill a child that runs away, which no alarm signal
inside a numba loop could. `simple` runs each job in the worker itself (no fork: 5 ms of RQ's
work a job instead of 20), its hard time limit kept by a timer thread (`softevo.worker.watchdog`).
BENCHMARKS.md (`bench/rq_workers.py`) compares it with the alternatives.
"""

from __future__ import annotations

import itertools
import logging
import os
import socket
import time
import uuid

from redis import Redis
from redis.exceptions import ConnectionError as RedisConnectionError
from redis.exceptions import TimeoutError as RedisTimeoutError
from rq import Queue, Worker

from softevo.worker.allow_list import job_class
from softevo.worker.queue import QUEUE, SERIALIZER, connect
from softevo.worker.watchdog import WatchedSimpleWorker

WORKER_CLASSES: dict[str, type] = {"fork": Worker, "simple": WatchedSimpleWorker}


def run_worker(
    redis_url: str,
    *,
    burst: bool = False,
    name: str | None = None,
    worker_class: str = "fork",
    queue: str = QUEUE,
    log_level: str = "INFO",
    allow: tuple[str, ...] = (),
) -> bool:
    """Warm up, then work until stopped (or, with `burst`, until the queue is empty)."""
    from softevo.core.physics.evaluation import warm_up

    started = time.perf_counter()
    warm_up()
    warm = time.perf_counter() - started
    log = logging.getLogger("softevo.worker")
    connection = connect(redis_url)
    connection.ping()  # fail now, with a clear error, if Redis is not there at the start
    base = name or f"{socket.gethostname()}.{os.getpid()}.{uuid.uuid4().hex[:6]}"
    cls = WORKER_CLASSES[worker_class]
    jobs = job_class(allow)  # softevo's job functions only (and `allow`), no callbacks
    for restart in itertools.count():
        # after Redis went away under a job, register afresh (the old name may still linger)
        worker = cls(
            [Queue(queue, connection=connection, serializer=SERIALIZER, job_class=jobs)],
            connection=connection,
            serializer=SERIALIZER,
            job_class=jobs,
            name=base if restart == 0 else f"{base}.r{restart}",
        )
        log.info("worker %s: kernels warm (%.2f s), taking jobs", worker.name, warm)
        try:
            return worker.work(burst=burst, logging_level=log_level, with_scheduler=False)
        except (RedisConnectionError, RedisTimeoutError) as error:
            log.warning("worker %s: lost Redis (%s); reconnecting", worker.name, error)
            _wait_for(connection)
    raise AssertionError("unreachable")


def _wait_for(connection: Redis, pause: float = 0.5) -> None:
    """Until Redis answers again."""
    while True:
        try:
            connection.ping()
            return
        except (RedisConnectionError, RedisTimeoutError):
            time.sleep(pause)
