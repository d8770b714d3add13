"""Server-sent events of one run: a `generation` event per committed generation (its curve row,
`id` = the generation, so a client reconnecting with Last-Event-ID resumes after it), a `status`
event when the status changes, and a final `end` event with the run once it has stopped."""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator, Callable
from typing import Any

from fastapi import Request
from starlette.concurrency import run_in_threadpool

from softevo.api import store
from softevo.api.db import Database
from softevo.core.status import FINAL

POLL_SECONDS = 0.25
KEEPALIVE_SECONDS = 15.0
TERMINAL = FINAL


def _event(name: str, data: Any, event_id: int | None = None) -> str:
    head = f"id: {event_id}\n" if event_id is not None else ""
    return f"{head}event: {name}\ndata: {json.dumps(data, default=str, allow_nan=False)}\n\n"


async def event_stream(
    request: Request,
    db: Database,
    run_id: int,
    after: int,
    public: Callable[[store.RunRecord], Any],
) -> AsyncIterator[str]:
    last_status = None
    idle = 0.0
    while True:
        run = await run_in_threadpool(store.get_run, db, run_id)
        rows = await run_in_threadpool(store.curve, db, run_id)
        for row in rows:
            if row["generation"] > after:
                after = row["generation"]
                idle = 0.0
                yield _event("generation", row, after)
        if run.status != last_status:
            last_status = run.status
            yield _event("status", {"run_id": run_id, "status": run.status})
        if run.status in TERMINAL:
            yield _event("end", (await run_in_threadpool(public, run)).model_dump(mode="json"))
            return
        if await request.is_disconnected():
            return
        await asyncio.sleep(POLL_SECONDS)
        idle += POLL_SECONDS
        if idle >= KEEPALIVE_SECONDS:
            idle = 0.0
            yield ": keep-alive\n\n"
