"""A live `softevo serve` for the dashboard's tests: a real process on a free port."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx

from softevo.local_service import service_env, start_service


@contextlib.contextmanager
def serve(folder: Path, token: str | None = None) -> Iterator[httpx.Client]:
    """`softevo serve` on a free port with a SQLite file in `folder`; a client for it."""
    settings = {
        "database_url": f"sqlite:///{folder / 'softevo.db'}",
        "workers": "1",
        "poll_seconds": "0.1",
    }
    if token:
        settings["api_token"] = token
    with (
        start_service(service_env(**settings), folder / "server.log") as local,
        httpx.Client(base_url=local.url, timeout=30) as client,
    ):
        yield client


def wait(predicate: Any, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, what
        time.sleep(0.1)
