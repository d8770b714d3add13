"""The RQ backend of the evaluator interface: batches become jobs on Redis, RQ workers on any
machine run them, and this side owns completion.

* A batch's job id is derived from its key (run, generation, content digest) and attempt, and
  every attempt pushes its result onto the same list: the first result wins, a late duplicate is
  never read twice, and the database accepts one fitness per individual anyway.
* A started job whose result has not come back within a deadline (from the measured seconds per
  unit of work, steps x voxels, not a fixed number) is presumed lost with its worker and enqueued
  again; a job that vanished (Redis restarted without persistence) is enqueued again; while
  Redis is away, this side waits and retries. RQ's own abandoned-job detection is not relied on.
* A batch whose job raised, or that ran out of attempts, is retried robot by robot, so only the
  robot that fails is marked failed (NaN), once; it never loops.
* A cancelled run's batches (`drop`) are given up: queued jobs deleted, started ones stopped.

Only redis, rq and numpy are imported here: the API process enqueues without loading the physics.
"""

from __future__ import annotations

import contextlib
import logging
import math
import threading
import time
from collections.abc import Iterator, Sequence
from datetime import UTC, datetime
from typing import Any

import numpy as np
from redis.exceptions import ConnectionError as RedisConnectionError
from redis.exceptions import TimeoutError as RedisTimeoutError
from rq import Queue, Worker
from rq.command import send_stop_job_command
from rq.exceptions import InvalidJobOperation, NoSuchJobError
from rq.job import Job, JobStatus

from softevo.core.evaluator import (
    BatchDroppedError,
    BatchResult,
    Evaluator,
    batch_digest,
    refuse_dropped,
)
from softevo.worker.outbox import Outbox
from softevo.worker.queue import (
    JOB_FUNCTION,
    QUEUE,
    REPLAY_FUNCTION,
    SERIALIZER,
    connect,
    engine_fingerprint,
    pop_result,
    result_key,
)
from softevo.worker.results import parse_result

log = logging.getLogger("softevo.rq")
REDIS_DOWN = (RedisConnectionError, RedisTimeoutError, ConnectionError, OSError)


class RQEvaluator(Evaluator):
    """Evaluates batches on RQ workers; thread-safe, any number of batches in flight."""

    def __init__(
        self,
        redis_url: str,
        *,
        queue: str = QUEUE,
        deadline_factor: float = 4.0,
        min_deadline: float = 5.0,
        initial_deadline: float = 30.0,
        max_attempts: int = 3,
        poll_seconds: float = 1.0,
        job_function: str = JOB_FUNCTION,
        engine: str | None = None,
    ) -> None:
        self.connection = connect(redis_url)
        self.queue = Queue(queue, connection=self.connection, serializer=SERIALIZER)
        self.outbox = Outbox(self.connection, self.queue)  # every thread's jobs, sent together
        self.deadline_factor = deadline_factor
        self.min_deadline = min_deadline
        self.initial_deadline = initial_deadline
        self.max_attempts = max_attempts
        self.poll_seconds = poll_seconds
        self.job_function = job_function
        self.engine = engine or engine_fingerprint()  # every job carries it (`SoftevoJob`)
        self._seconds_per_unit: float | None = None  # measured: see `work_units`
        self._held_since: dict[str, float] = {}  # job id -> when first seen taken, not started
        self._lock = threading.Lock()
        self._workers = (1, -math.inf)  # (live workers on the queue, when counted)
        self._empty_since: float | None = None  # when the count was first seen 0
        self._dropped: set[str] = set()  # key prefixes given up (`drop`)

    # -- the interface -------------------------------------------------------------------------

    def evaluate_batch(
        self, robot_files: Sequence[dict[str, Any]], key: str | None = None
    ) -> BatchResult:
        files = list(robot_files)
        if not files:
            return BatchResult(np.empty(0), "", 0.0)
        key = key or batch_digest(files)
        payload = self.collect(files, key)
        if "refused" in payload:  # a worker of another engine: never a silently other curve
            raise EngineMismatchError(str(payload["refused"]))
        worker = str(payload.get("worker", ""))
        if "fitness" in payload:
            return BatchResult.measured(payload, worker, float(payload["seconds"]))
        if len(files) == 1:
            log.warning("batch %s failed for good: %s", key, payload.get("error"))
            return BatchResult(np.array([math.nan]), worker, 0.0)
        log.warning("batch %s failed (%s); retrying robot by robot", key, payload.get("error"))
        parts = [self.evaluate_batch([file], f"{key}-{i}") for i, file in enumerate(files)]
        return BatchResult(
            np.concatenate([part.fitness for part in parts]),
            ",".join(sorted({part.worker for part in parts if part.worker})),
            sum(part.seconds for part in parts),
            [record for part in parts for record in part.records()],
        )

    def capacity(self) -> int:
        """Workers registered on the queue, counted at most every 5 s (the last count, or 1,
        while Redis is away): batches are cut so that each of them can have one."""
        return max(1, self._count())

    def _count(self) -> int:
        """Live workers on the queue (the last count while Redis is away), at most every 5 s."""
        count, when = self._workers
        if time.monotonic() - when < 5.0:
            return count
        with contextlib.suppress(*REDIS_DOWN):
            count = Worker.count(connection=self.connection, queue=self.queue)
            if count > 0:
                self._empty_since = None
            elif self._empty_since is None:
                self._empty_since = time.monotonic()
        self._workers = (count, time.monotonic())
        return count

    def without_workers(self) -> float:
        """Seconds the queue has had no live worker (0 while it has one): the service says so
        in `/healthz` and on its runs past a deadline, instead of waiting in silence."""
        self._count()
        return 0.0 if self._empty_since is None else time.monotonic() - self._empty_since

    def drop(self, key_prefix: str) -> None:
        """Give up a cancelled run's batches: each waiting `collect` of theirs, within
        `poll_seconds`, deletes its queued jobs, stops its started ones on their workers (RQ's
        stop-job command: the forking worker kills its work horse; a `simple` worker has none
        and finishes the job, its result unread) and raises `BatchDroppedError`."""
        with self._lock:
            self._dropped.add(key_prefix)

    def _give_up_if_dropped(self, key: str, attempts: int) -> None:
        with self._lock:
            prefixes = set(self._dropped)
        try:
            refuse_dropped(key, prefixes)
        except BatchDroppedError:
            for job in self._attempts(key, attempts):
                with contextlib.suppress(InvalidJobOperation, *REDIS_DOWN):
                    if job.get_status(refresh=False) == JobStatus.STARTED:
                        send_stop_job_command(self.connection, job.id, serializer=SERIALIZER)
                    else:
                        job.delete()
            raise

    def _attempts(self, key: str, attempts: int, skip: Any = None) -> Iterator[Job]:
        """The batch's jobs still on Redis, attempt 1 to `attempts` (none while it is away),
        but the one whose id is `skip` (not fetched)."""
        for n in range(1, attempts + 1):
            job_id = f"softevo-{key}-a{n}"
            if job_id == skip:
                continue
            try:
                job = Job.fetch(job_id, connection=self.connection, serializer=SERIALIZER)
            except (NoSuchJobError, *REDIS_DOWN):
                continue
            yield job

    def close(self) -> None:
        self.connection.close()

    # -- completion ----------------------------------------------------------------------------

    def expected_seconds(self, files: list[dict[str, Any]]) -> float | None:
        """What the batch should take on a worker, from the measured seconds per work unit."""
        with self._lock:
            per_unit = self._seconds_per_unit
        return None if per_unit is None else per_unit * sum(map(work_units, files))

    def deadline(self, files: list[dict[str, Any]]) -> float:
        """Seconds a started job may run before it is presumed lost."""
        expected = self.expected_seconds(files)
        if expected is None:
            return self.initial_deadline
        return max(self.min_deadline, self.deadline_factor * expected)

    def _learn(self, payload: dict[str, Any], files: list[dict[str, Any]]) -> None:
        seconds = payload.get("seconds")
        units = sum(map(work_units, files))
        if "fitness" not in payload or units <= 0 or not isinstance(seconds, int | float):
            return
        sample = float(seconds) / units
        with self._lock:
            old = self._seconds_per_unit
            self._seconds_per_unit = sample if old is None else 0.7 * old + 0.3 * sample

    def _enqueue(
        self, files: list[dict[str, Any]], key: str, attempt: int, extra: tuple = ()
    ) -> str:
        job_id = f"softevo-{key}-a{attempt}"
        expected = self.expected_seconds(files)
        # RQ kills a work horse 60 s after this: the hard limit for a job that runs away
        timeout = 600 if expected is None else max(60, math.ceil(20 * expected))
        # the description is said, or RQ would build it from the repr of every robot file (about
        # a tenth of the enqueue's CPU), and rq-dashboard shows the batch's key instead; the
        # outbox sends it with the other threads' jobs, one round trip for all
        self.outbox.send(
            Queue.prepare_data(
                self.job_function,
                args=(key, files, *extra),
                job_id=job_id,
                timeout=timeout,
                description=f"softevo {self.job_function.rsplit('.', 1)[-1]} {key} ({len(files)})",
                meta={"engine": self.engine},
                result_ttl=600,
                failure_ttl=3600,
            )
        )
        return job_id

    def collect(
        self,
        files: list[dict[str, Any]],
        key: str,
        extra: tuple = (),
        timeout: float | None = None,
    ) -> dict[str, Any]:
        """The job's payload (`job_function(key, files, *extra)`): the first result of any
        attempt, enqueueing again what is lost; `{"error": ...}` when every attempt failed or,
        with `timeout` (s), when none came back in time (no live worker, say)."""
        attempt, job_id = 1, None
        late: set[str] = set()  # attempts presumed lost with their worker
        started = time.monotonic()
        while True:
            self._give_up_if_dropped(key, attempt)
            if timeout is not None and time.monotonic() - started > timeout:
                self._retire(key, attempt, late | {f"softevo-{key}-a{attempt}"}, None)
                return {"error": f"no result in {timeout:g} s (are workers running?)"}
            try:
                if job_id is None:
                    job_id = self._enqueue(files, key, attempt, extra)
                item = pop_result(self.connection, result_key(key), self.poll_seconds)
                payload = None if item is None else parse_result(item[1], len(files))
                if payload is not None:
                    self._learn(payload, files)
                    self._retire(key, attempt, late, payload.get("job"))
                    return payload
                if item is not None:
                    log.warning("batch %s: ignored a malformed result %.80r", key, item[1])
                    continue
                verdict = self._check(job_id, files)
            except REDIS_DOWN as error:
                log.warning("redis unavailable (%s); batch %s waits", type(error).__name__, key)
                time.sleep(self.poll_seconds)
                continue
            if verdict == "vanished":
                log.warning("job %s vanished (Redis restarted?); enqueueing it again", job_id)
                job_id = None
            elif verdict in ("failed", "late"):
                if verdict == "late":
                    late.add(job_id)
                if attempt >= self.max_attempts:
                    self._retire(key, attempt, late, None)
                    return {"error": f"{verdict} after {attempt} attempts"}
                log.warning("job %s %s; enqueueing attempt %d", job_id, verdict, attempt + 1)
                attempt, job_id = attempt + 1, None

    def _retire(self, key: str, attempts: int, late: set[str], winner: Any) -> None:
        """Once a batch is settled, take its other attempts off Redis: a queued one would only
        waste a worker, and one presumed lost (its worker killed) would otherwise sit in RQ's
        StartedJobRegistry until RQ's own clean-up, minutes later. A copy still running on a
        live worker finishes all the same; its late result is never read. The winner is not
        fetched: a batch settled by its first attempt (nearly all) costs no round trip here."""
        for job in self._attempts(key, attempts, skip=winner):
            with contextlib.suppress(NoSuchJobError, *REDIS_DOWN):
                status = job.get_status(refresh=False)
                if status == JobStatus.QUEUED or (status == JobStatus.STARTED and job.id in late):
                    job.delete()

    def _check(self, job_id: str, files: list[dict[str, Any]]) -> str:
        """waiting | vanished | failed | late, for a job whose result has not come back."""
        try:
            job = Job.fetch(job_id, connection=self.connection, serializer=SERIALIZER)
        except NoSuchJobError:
            return "vanished"
        status = job.get_status(refresh=False)
        if status == JobStatus.FINISHED and not self.connection.llen(result_key(key_of(job_id))):
            # The job pushes its result before RQ marks it finished, so a finished job with an
            # empty result list lost its result (the list expired or was lost, or what it pushed
            # was malformed and skipped): another attempt, counted, so it can never loop.
            return "failed"
        if status in (JobStatus.FAILED, JobStatus.STOPPED, JobStatus.CANCELED):
            return "failed"
        if status == JobStatus.QUEUED:
            # A worker takes a job by moving it to an intermediate list, then marks it started
            # within milliseconds. One frozen in between (SIGSTOP while idle) holds the job with
            # no deadline of RQ's own; give it `min_deadline` to start.
            held = self.connection.lpos(self.queue.intermediate_queue_key, job_id) is not None
            now = time.monotonic()
            with self._lock:
                since = self._held_since.setdefault(job_id, now) if held else None
                if not held:
                    self._held_since.pop(job_id, None)
            if since is not None and now - since > self.min_deadline:
                with self._lock:
                    self._held_since.pop(job_id, None)
                return "late"
        if status == JobStatus.STARTED and job.started_at is not None:
            started = job.started_at
            if started.tzinfo is None:
                started = started.replace(tzinfo=UTC)
            running = (datetime.now(UTC) - started).total_seconds()
            if running > self.deadline(files):
                return "late"
        return "waiting"


def key_of(job_id: str) -> str:
    """The batch key of job id `softevo-{key}-a{attempt}`."""
    return job_id.removeprefix("softevo-").rsplit("-a", 1)[0]


def work_units(robot_file: dict[str, Any]) -> float:
    """A robot's simulation cost in arbitrary units: integration steps x occupied voxels (the
    springs grow with them), so one measured rate gives deadlines for robots of any size."""
    try:
        sim = robot_file.get("sim", {})
        steps = float(sim.get("duration", 10.0)) / float(sim.get("dt", 0.0005))
        labels = list(robot_file.get("voxels") or [])  # counted in C, not by a generator
        size = len(labels) - labels.count("empty") or len(robot_file.get("springs", [])) / 28
        units = steps * max(1.0, float(size))
    except (AttributeError, TypeError, ValueError, ZeroDivisionError):
        return 1.0
    return units if math.isfinite(units) and units > 0 else 1.0


class EngineMismatchError(RuntimeError):
    """A worker computes with another engine (softevo, numpy, numba or llvmlite version) than
    this side: the run fails, saying both, rather than mixing fitness of two engines."""


class ReplayUnavailableError(RuntimeError):
    """The workers gave no replay (none live in time, or the job failed): a 503, said why."""


class RQReplayer:
    """Replays computed by the RQ workers (`softevo.worker.jobs.replay`), with the same
    completion as batches (lost jobs enqueued again, a failed one said), so the API process
    never loads the physics. Called as `softevo.api.replay`'s remote: (robot file, fps, max
    positions)."""

    def __init__(self, redis_url: str, timeout: float = 600.0) -> None:
        # a replay records frames and may take minutes: a generous first deadline
        self.rq = RQEvaluator(
            redis_url, job_function=REPLAY_FUNCTION, initial_deadline=300.0, max_attempts=2
        )
        self.timeout = timeout  # a GET never waits longer, with or without workers

    def __call__(self, robot_file: dict[str, Any], fps: float, max_positions: int) -> dict:
        key = f"replay-{batch_digest([robot_file])}-{fps:g}-{max_positions}"
        payload = self.rq.collect([robot_file], key, (fps, max_positions), self.timeout)
        if "replay" not in payload:
            raise ReplayUnavailableError(
                f"the replay failed on the workers: {payload.get('error')}"
            )
        return payload["replay"]

    def close(self) -> None:
        self.rq.close()
