"""The service `softevo reproduce` talks to: a running one (`--url`) or a private `softevo
serve` on a SQLite file in the output folder, through `softevo.client`."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

from softevo.client import Client
from softevo.local_service import ServiceError, start_service


@contextlib.contextmanager
def service(
    url: str | None, out: Path, workers: int | None, resume: bool = False
) -> Iterator[Client]:
    """A client of `url` (token from SOFTEVO_API_TOKEN), or of a private `softevo serve` on a
    SQLite file in `out` (kept with `resume`, else started afresh)."""
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
        "SOFTEVO_MAX_RUNNING": "2",
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
