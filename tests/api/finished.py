"""Waiting for a run through the API's own client, the one helper the service tests share."""

from __future__ import annotations

import time

from fastapi.testclient import TestClient


def finished(client: TestClient, run_id: int, timeout: float = 60) -> dict:
    """The run once it is no longer queued or running (AssertionError after `timeout` s)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        run = client.get(f"/runs/{run_id}").json()
        if run["status"] not in ("queued", "running"):
            return run
        time.sleep(0.05)
    raise AssertionError(f"run {run_id} still {run['status']}")
