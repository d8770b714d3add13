"""Server-sent events of one run: a `generation` event per committed generation (its curve row,
`id` = the generation, so a client reconnecting with Last-Event-ID resumes after it), a `status`
event when the status changes, and a final `end` event with the run once it has stopped.

One watcher per run, however many clients follow it: it polls the database (the run, and only
the curve rows it has not seen) and every client of the run is woken from what it read, so 200
clients cost what one does. The number of clients of this process is capped
(SOFTEVO_MAX_EVENT_CLIENTS); past it, 503.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import AsyncIterator, Callable
from typing import Any

from fastapi import Request
from starlette.concurrency import run_in_threadpool

from softevo.api import store
from softevo.api.db import Database
from softevo.core.status import FINAL

log = logging.getLogger("softevo.events")
POLL_SECONDS = 0.25
KEEPALIVE_SECONDS = 15.0
TERMINAL = FINAL


class TooManyClientsError(RuntimeError):
    """This process follows as many event clients as it may (503)."""


def _event(name: str, data: Any, event_id: int | None = None) -> str:
    head = f"id: {event_id}\n" if event_id is not None else ""
    return f"{head}event: {name}\ndata: {json.dumps(data, default=str, allow_nan=False)}\n\n"


class RunWatch:
    """What the database says of one run, read by one task for all of the run's clients."""

    def __init__(self, db: Database, run_id: int, public: Callable[[Any], Any]) -> None:
        self.db, self.run_id, self.public = db, run_id, public
        self.rows: list[dict[str, Any]] = []
        self.status: str | None = None
        self.end: dict[str, Any] | None = None  # the run as `end` sends it, once it stopped
        self.version = 0
        self.clients = 0
        self.changed = asyncio.Event()
        self.task: asyncio.Task[None] | None = None

    async def poll(self) -> None:
        while self.clients > 0:
            try:
                if await self._read():
                    return
            except Exception:  # the database away, say: its clients wait, and it tries again
                log.warning("events of run %s: cannot read the run", self.run_id, exc_info=True)
            await asyncio.sleep(POLL_SECONDS)

    async def _read(self) -> bool:
        """One look at the database; True once the run has stopped and `end` is known."""
        run = await run_in_threadpool(store.get_run, self.db, self.run_id)
        after = self.rows[-1]["generation"] if self.rows else -1
        new = await run_in_threadpool(store.curve_after, self.db, self.run_id, after)
        if run.status in TERMINAL:
            public = await run_in_threadpool(self.public, run)
            self.end = public.model_dump(mode="json")
        if new or run.status != self.status or self.end is not None:
            self.rows.extend(new)
            self.status = run.status
            self.version += 1
            self.changed.set()
            self.changed = asyncio.Event()
        return self.end is not None


class Watches:
    """The watchers of this process, one per followed run, and the client count's cap."""

    def __init__(self, db: Database, max_clients: int) -> None:
        self.db, self.max_clients = db, max_clients
        self.runs: dict[int, RunWatch] = {}

    @property
    def clients(self) -> int:
        return sum(watch.clients for watch in self.runs.values())

    def check_room(self) -> None:
        if self.clients >= self.max_clients:
            raise TooManyClientsError(
                f"{self.clients} event streams are open, the most this server follows "
                "(SOFTEVO_MAX_EVENT_CLIENTS); try again later or poll GET /runs/{id}"
            )

    def join(self, run_id: int, public: Callable[[Any], Any]) -> RunWatch:
        watch = self.runs.get(run_id)
        if watch is None or (watch.task is not None and watch.task.done()):
            watch = self.runs[run_id] = RunWatch(self.db, run_id, public)
        watch.clients += 1
        if watch.task is None:
            watch.task = asyncio.get_running_loop().create_task(watch.poll())
        return watch

    def leave(self, watch: RunWatch) -> None:
        watch.clients -= 1
        if watch.clients <= 0 and self.runs.get(watch.run_id) is watch:
            del self.runs[watch.run_id]


async def event_stream(
    request: Request,
    watches: Watches,
    run_id: int,
    after: int,
    public: Callable[[store.RunRecord], Any],
) -> AsyncIterator[str]:
    watch = watches.join(run_id, public)
    seen_version, status = -1, None
    try:
        while True:
            if watch.version == seen_version:
                changed = watch.changed
                try:
                    await asyncio.wait_for(changed.wait(), KEEPALIVE_SECONDS)
                except TimeoutError:
                    if await request.is_disconnected():
                        return
                    yield ": keep-alive\n\n"
                continue
            seen_version = watch.version
            for row in watch.rows[after + 1 :]:  # rows are generations 0, 1, 2, ... in order
                after = row["generation"]
                yield _event("generation", row, after)
            if watch.status != status:
                status = watch.status
                yield _event("status", {"run_id": run_id, "status": status})
            if watch.end is not None:
                yield _event("end", watch.end)
                return
            if await request.is_disconnected():
                return
    finally:
        watches.leave(watch)
