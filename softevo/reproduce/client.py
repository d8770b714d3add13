"""The service `softevo reproduce` talks to: a running one (`--url`) or a private `softevo
serve` on a SQLite file in the output folder, through `softevo.client`."""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from softevo.client import Client
from softevo.local_service import ServiceError, start_service
from softevo.reproduce.plan import FINAL


@contextlib.contextmanager
def service(
    url: str | None, out: Path, workers: int | None, resume: bool = False, running: int = 2
) -> Iterator[Client]:
    """A client of `url` (token from SOFTEVO_API_TOKEN), or of a private `softevo serve` on a
    SQLite file in `out` (kept with `resume`, else started afresh) that drives `running` runs
    at a time (1: each run's wall time is its own, with every core to itself)."""
    if url:
        with Client(url, token=os.environ.get("SOFTEVO_API_TOKEN")) as client:
            yield client
        return
    if not resume:
        for stale in out.glob("softevo.db*"):
            stale.unlink()
    env = {
        **os.environ,
        "SOFTEVO_DATABASE_URL": f"sqlite:///{out / 'softevo.db'}",
        "SOFTEVO_MAX_RUNNING": str(running),
        "SOFTEVO_MAX_QUEUED": "10000",
    }
    env.pop("SOFTEVO_REDIS_URL", None)
    env.pop("SOFTEVO_API_TOKEN", None)
    if workers:
        env["SOFTEVO_WORKERS"] = str(workers)
    try:
        local = start_service(env, out / "service.log", "--log-level", "warning", timeout=120)
    except ServiceError as error:
        raise SystemExit(f"softevo reproduce: {error}") from None
    with local, Client(local.url) as client:
        yield client


def wait_runs(client: Client, run_ids: list[int], what: str) -> list[dict[str, Any]]:
    """Every run's final status, in order, saying `what: k/n runs done` as the count grows."""
    last = -1
    while True:
        runs = [client.get_run(i).status() for i in run_ids]
        done = sum(r["status"] in FINAL for r in runs)
        if done != last:
            print(f"  {what}: {done}/{len(runs)} runs done", flush=True)
            last = done
        if done == len(runs):
            return runs
        time.sleep(2)
