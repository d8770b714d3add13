"""The service `softevo reproduce` talks to: a running one (`--url`) or a private `softevo
serve` on a SQLite file in the output folder."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx

from softevo.local_service import ServiceError, start_service


@contextlib.contextmanager
def service(
    url: str | None, out: Path, workers: int | None, resume: bool = False
) -> Iterator[httpx.Client]:
    """A client of `url`, or of a private `softevo serve` on a SQLite file in `out` (kept with
    `resume`, else started afresh)."""
    token = os.environ.get("SOFTEVO_API_TOKEN")
    headers = {"Authorization": f"Bearer {token}"} if token else {}
    if url:
        with httpx.Client(base_url=url, headers=headers, timeout=60) as client:
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
    with local, httpx.Client(base_url=local.url, timeout=60) as client:
        yield client


def checked(response: httpx.Response) -> Any:
    if response.status_code >= 400:
        raise SystemExit(
            f"softevo reproduce: {response.request.method} {response.request.url.path} "
            f"answered {response.status_code}: {response.text[:500]}"
        )
    return response.json()
