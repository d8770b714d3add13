"""Jobs from every batch thread sent to Redis together (issue 52).

Each batch thread used to enqueue its own job: RQ's `Job` built, its hash packed, one round trip
a job. Here a thread that finds no send under way takes every job gathered so far (its own and
any other thread's) and sends them with RQ's `enqueue_many` in one pipeline: one round trip for
them all, and the queue's set written once. The threads whose jobs it took wait for it; a thread
whose job came in while it sent becomes the next sender. Nothing waits for company: a job alone
goes at once, so the outbox adds no latency, only fewer round trips when jobs come together (a
generation's batches, or several results landing at once).

A send that fails (Redis away) fails for every job it held, and each thread handles it as its
own enqueue's failure: it waits and enqueues again.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

from redis import Redis
from rq import Queue
from rq.queue import EnqueueData


@dataclass
class _Letter:
    data: EnqueueData
    sent: bool = False
    error: BaseException | None = None


class Outbox:
    """Thread-safe: `send` returns once the job is on Redis, or raises what its send raised."""

    def __init__(self, connection: Redis, queue: Queue) -> None:
        self.connection = connection
        self.queue = queue
        self._changed = threading.Condition()
        self._pending: list[_Letter] = []
        self._busy = False  # a thread is sending
        self.sends = 0  # round trips made, and jobs sent by them (`bench/scaling.py` reads both)
        self.jobs = 0

    def send(self, data: EnqueueData) -> None:
        letter = _Letter(data)
        batch: list[_Letter] = []
        with self._changed:
            self._pending.append(letter)
            while self._busy and not letter.sent:
                self._changed.wait()
            if not letter.sent:  # no send under way: this thread sends what has gathered
                self._busy = True
                batch, self._pending = self._pending, []
        if batch:
            self._send(batch)
        if letter.error is not None:
            raise letter.error

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
        with self._changed:
            for letter in batch:
                letter.sent, letter.error = True, error
            self.sends += 1
            self.jobs += len(batch)
            self._busy = False
            self._changed.notify_all()
