"""What both sides of the queue agree on: the queue's name, the job's import path, the keys
results land on, and how to connect. Jobs and results are JSON (RQ's JSONSerializer), never
pickles, so nothing read from Redis can run code in the API process."""

from __future__ import annotations

import json
from typing import cast
from urllib.parse import urlsplit, urlunsplit

from redis import Redis
from rq.serializers import JSONSerializer

QUEUE = "softevo"
#: Named by import path, so the process that enqueues never imports the physics.
JOB_FUNCTION = "softevo.worker.jobs.evaluate_batch"
REPLAY_FUNCTION = "softevo.worker.jobs.replay"
#: What a worker runs (`softevo.worker.allow_list.SoftevoJob`): these, and nothing else by default.
JOB_FUNCTIONS = frozenset({JOB_FUNCTION, REPLAY_FUNCTION})
SERIALIZER = JSONSerializer
#: How long a batch's result waits to be collected (s); a late duplicate expires with it.
RESULT_TTL = 3600


def engine_fingerprint() -> str:
    """What shapes a fitness's arithmetic: softevo's version and those of numpy, numba and
    llvmlite. A job carries the API's; a worker with another refuses it, so one run is computed
    by one engine (read from package metadata: the physics is not imported for it)."""
    from importlib.metadata import PackageNotFoundError, version

    parts = []
    for package in ("softevo", "numpy", "numba", "llvmlite"):
        try:
            parts.append(f"{package} {version(package)}")
        except PackageNotFoundError:
            parts.append(f"{package} ?")
    return ", ".join(parts)


def result_key(batch_key: str) -> str:
    """The Redis list a batch's results are pushed onto, by whichever attempt finishes first."""
    return f"softevo:result:{batch_key}"


def push_result(connection: Redis, batch_key: str, payload: dict) -> None:
    """Push `payload` (JSON) onto the batch's result list, which expires with RESULT_TTL."""
    pipe = connection.pipeline()
    pipe.rpush(result_key(batch_key), json.dumps(payload))
    pipe.expire(result_key(batch_key), RESULT_TTL)
    pipe.execute()


def redacted(url: str) -> str:
    """The URL with its password hidden, for messages and logs."""
    parts = urlsplit(url)
    if parts.password is None:
        return url
    netloc = parts.netloc.replace(f":{parts.password}@", ":***@", 1)
    return urlunsplit(parts._replace(netloc=netloc))


def connect(url: str) -> Redis:
    return Redis.from_url(
        url, socket_connect_timeout=5, socket_keepalive=True, health_check_interval=30
    )


def pop_result(connection: Redis, key: str, timeout: float) -> tuple[bytes, bytes] | None:
    """The next result pushed onto `key`'s list, waiting up to `timeout` s; None if none came.
    (redis-py types its commands for the sync and asyncio clients at once; this one is sync.)"""
    return cast("tuple[bytes, bytes] | None", connection.blpop([key], timeout=timeout))
