"""The `simple` worker's hard time limit. RQ's SimpleWorker runs a job in the worker process
itself, and its alarm signal cannot interrupt a numba loop, so a run-away simulation would hold
the worker for good. The kernels release the GIL (`core.physics.jit.JIT`, nogil), so a timer
thread still runs beside them: once a job is past its timeout by as much again (60 s at most,
like the forking worker's parent), it says so on the batch's result list (the API side then
retries the batch robot by robot, so only the robot that hangs fails), marks the job failed,
and the worker starts afresh in the same process (`os.execv`, kernels loaded from the cache).
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import threading
import time
from typing import Any

from redis.exceptions import RedisError
from rq import SimpleWorker
from rq.job import Job
from rq.queue import Queue

from softevo.worker.queue import push_result

log = logging.getLogger("softevo.worker")
#: The most a job may run past its timeout before the worker gives it up (the fork worker's).
MAX_GRACE = 60.0


def hard_limit(timeout: Any) -> float | None:
    """Seconds after which a job of RQ timeout `timeout` is given up (None: never)."""
    if not isinstance(timeout, int | float) or timeout <= 0:
        return None
    return float(timeout) + min(MAX_GRACE, float(timeout))


class WatchedSimpleWorker(SimpleWorker):
    """RQ's SimpleWorker with a hard time limit per job (this module's docstring)."""

    def execute_job(self, job: Job, queue: Queue) -> None:
        limit = hard_limit(job.timeout)
        if limit is None:
            return super().execute_job(job, queue)
        timer = threading.Timer(limit, self._give_up, (job, queue, limit, time.monotonic()))
        timer.daemon = True
        timer.start()
        try:
            return super().execute_job(job, queue)
        finally:
            timer.cancel()

    def _give_up(self, job: Job, queue: Queue, limit: float, started: float) -> None:
        """Runs on the timer's thread while the job still holds the worker's main thread."""
        seconds = time.monotonic() - started
        message = f"JobTimeout: ran past its hard limit of {limit:g} s; the worker restarts"
        log.warning("job %s %s", job.id, message)
        key = job.args[0] if job.args and isinstance(job.args[0], str) else None
        robots = len(job.args[1]) if len(job.args) > 1 and isinstance(job.args[1], list) else 0
        with contextlib.suppress(RedisError):
            # failed before it is said: whoever reads the result finds the job failed
            self.handle_job_failure(job, queue, exc_string=message, execution=self.execution)
            if key is not None:
                payload = {"error": message, "worker": self.name, "seconds": seconds}
                push_result(self.connection, key, {**payload, "robots": robots, "job": job.id})
            self.register_death()
        restart()


def restart() -> None:
    """The same command line again, in this process (its pid kept for whoever watches it)."""
    logging.shutdown()
    sys.stdout.flush()
    sys.stderr.flush()
    os.execv(sys.executable, [sys.executable, *sys.orig_argv[1:]])
