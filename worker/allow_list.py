"""The allow list: the job class every `softevo worker` uses runs softevo's own job functions
and nothing else. RQ names a job's function and callbacks by import path, so anyone who can
write to Redis could otherwise have a worker run `os.system`; such a job fails here, before
anything is imported, with a log line, and the worker goes on with the next job. A job hash
that cannot be read at all is moved aside (`softevo:malformed:<id>`), logged, and skipped."""

from __future__ import annotations

import contextlib
import logging
from typing import Any, ClassVar

from redis.exceptions import RedisError
from rq.exceptions import NoSuchJobError
from rq.job import Job

from softevo.worker.queue import JOB_FUNCTIONS, engine_fingerprint, push_result

log = logging.getLogger("softevo.worker")
ENGINE = engine_fingerprint()
#: Where a job hash that cannot be read is kept for inspection (a week), instead of the queue.
MALFORMED_PREFIX = "softevo:malformed:"
MALFORMED_TTL = 7 * 24 * 3600


class RefusedJobError(RuntimeError):
    """A job that names a function softevo does not run, or any callback."""


class SoftevoJob(Job):
    """An RQ job restricted to `allowed` functions, with no callbacks; a job hash that cannot be
    read (garbage dates, data or fields) is moved aside instead of stopping the worker."""

    allowed: ClassVar[frozenset[str]] = JOB_FUNCTIONS

    def restore(self, raw_data: Any) -> Any:
        try:
            return super().restore(raw_data)
        except Exception as error:  # whatever is in the hash, never a reason for the worker to stop
            moved = f"{MALFORMED_PREFIX}{self.id}"
            with contextlib.suppress(RedisError):
                self.connection.rename(self.key, moved)
                self.connection.expire(moved, MALFORMED_TTL)
            log.warning("malformed job %s moved aside to %s: %s", self.id, moved, error)
            raise NoSuchJobError(f"job {self.id} is malformed and was moved aside") from None

    @property
    def func(self) -> Any:
        callbacks = [
            name
            for name in (
                self._success_callback_name,
                self._failure_callback_name,
                self._stopped_callback_name,
            )
            if name
        ]
        engine = (self.meta or {}).get("engine")
        if self.func_name in self.allowed and not callbacks and engine != ENGINE:
            self._refuse_engine(engine)
        if self.func_name not in self.allowed or self.instance is not None or callbacks:
            what = f"function {self.func_name!r}" + (
                f", callbacks {callbacks}" if callbacks else ""
            )
            log.warning("refused job %s: %s is not one of softevo's jobs", self.id, what)
            raise RefusedJobError(f"refused: {what} is not one of softevo's jobs")
        return super().func

    def _refuse_engine(self, engine: Any) -> None:
        """Another engine asked: said in the log and on the batch's result list (the API then
        fails the run with both fingerprints), and the job fails."""
        message = f"this worker computes with [{ENGINE}], the job was sent by [{engine}]"
        log.warning("refused job %s: %s", self.id, message)
        key = self.args[0] if self.args and isinstance(self.args[0], str) else None
        if key is not None:
            payload = {"refused": message, "worker": self.worker_name or "", "job": self.id}
            with contextlib.suppress(RedisError):
                push_result(self.connection, key, payload)
        raise RefusedJobError(f"refused: {message}")

    # callbacks are never imported or run (a job that names one is refused above)
    @property
    def success_callback(self) -> None:
        return None

    @property
    def failure_callback(self) -> None:
        return None

    @property
    def stopped_callback(self) -> None:
        return None


def job_class(also: tuple[str, ...] = ()) -> type[SoftevoJob]:
    """SoftevoJob, allowing `also` (dotted function names: tests, extensions) besides."""
    if not also:
        return SoftevoJob
    return type("SoftevoJob", (SoftevoJob,), {"allowed": JOB_FUNCTIONS | frozenset(also)})
