"""A live `softevo serve` for the dashboard's tests: a real process on a free port."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx

from tests.services import free_port


@contextlib.contextmanager
def serve(folder: Path, token: str | None = None) -> Iterator[httpx.Client]:
    """`softevo serve` on a free port with a SQLite file in `folder`; a client for it."""
    port = free_port()
    env = {
        **os.environ,
        "SOFTEVO_DATABASE_URL": f"sqlite:///{folder / 'softevo.db'}",
        "SOFTEVO_WORKERS": "1",
        "SOFTEVO_POLL_SECONDS": "0.1",
    }
    env.pop("SOFTEVO_REDIS_URL", None)
    env.pop("SOFTEVO_API_TOKEN", None)
    if token:
        env["SOFTEVO_API_TOKEN"] = token
    log = (folder / "server.log").open("wb")
    process = subprocess.Popen(
        [sys.executable, "-P", "-m", "softevo.cli", "serve", "--port", str(port)],
        env=env,
        stdout=log,
        stderr=subprocess.STDOUT,
    )
    client = httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=30)
    try:
        deadline = time.monotonic() + 60
        while True:
            assert process.poll() is None, (folder / "server.log").read_text()
            try:
                if client.get("/healthz").status_code == 200:
                    break
            except httpx.TransportError:
                pass
            assert time.monotonic() < deadline, "softevo serve did not start"
            time.sleep(0.1)
        yield client
    finally:
        process.terminate()
        process.wait(20)
        log.close()
        client.close()


def wait(predicate: Any, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, what
        time.sleep(0.1)
