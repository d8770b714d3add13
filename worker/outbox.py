"""Jobs from every batch thread sent to Redis together (issue 52).

Each batch thread used to enqueue its own job: RQ's `Job` built, its hash packed, one round trip
a job. Here a thread that finds no send under way becomes the sender: it sends the jobs
gathered (its own and any other thread's), up to `MOST` at a time, with RQ's `enqueue_many` in
one pipeline, one round trip each, until none is left. The threads whose jobs it sends wait for
theirs, each woken alone. Nothing waits for company: a job alone goes at once, so the outbox
adds no latency, only fewer round trips when jobs come together (a generation's batches, or
several results landing at once).

A send that fails (Redis away) fails for every job it held, and each thread handles it as its
own enqueue's failure: it waits and enqueues again.
"""

from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass, field

from redis import Redis
from rq import Queue
from rq.queue import EnqueueData

#: Most jobs in one pipeline: the first of them reaches a worker only once the pipeline is
#: built and sent, so a generation's 50 batches go as several sends, not one long one.
MOST = 8


@dataclass
class _Letter:
    data: EnqueueData
    sent: threading.Event = field(default_factory=threading.Event)
    error: BaseException | None = None


class Outbox:
    """Thread-safe: `send` returns once the job is on Redis, or raises what its send raised."""

    def __init__(self, connection: Redis, queue: Queue) -> None:
        self.connection = connection
        self.queue = queue
        self._lock = threading.Lock()
        self._pending: deque[_Letter] = deque()
        self._busy = False  # a thread is sending
        self.sends = 0  # round trips made, and the jobs they sent (what batching saved)
        self.jobs = 0

    def send(self, data: EnqueueData) -> None:
        letter = _Letter(data)
        with self._lock:
            self._pending.append(letter)
            lead, self._busy = not self._busy, True
        if lead:  # no send under way: this thread sends until none is left (its own first)
            while batch := self._take():
                self._send(batch)
        letter.sent.wait()  # set by whichever thread sent it (at once, if this one did)
        if letter.error is not None:
            raise letter.error

    def _take(self) -> list[_Letter]:
        """The next jobs to send, oldest first; none left: the send is over."""
        with self._lock:
            batch = [self._pending.popleft() for _ in range(min(MOST, len(self._pending)))]
            self._busy = bool(batch)
        return batch

    def _send(self, batch: list[_Letter]) -> None:
        error: BaseException | None = None
        try:
            # one job per id (two GETs of one replay ask for the same job): the last one asked
            unique = {letter.data.job_id: letter.data for letter in batch}
            with self.connection.pipeline() as pipe:
                self.queue.enqueue_many(list(unique.values()), pipeline=pipe)
                pipe.execute()
        except BaseException as raised:  # every thread of the batch gets it
            error = raised
        self.sends += 1  # the sender alone writes these
        self.jobs += len(batch)
        for letter in batch:
            letter.error = error
            letter.sent.set()
