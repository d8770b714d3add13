"""A write fault under a live `softevo serve`, said and survived: the one procedure of the
read-only-database and full-disk tests (`test_database_faults.py`, `test_disk_faults.py`)."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import httpx

from softevo.local_service import start_service

AUTH = {"Authorization": "Bearer t"}  # the token the tests' services are started with


def said_and_survived(
    env: Mapping[str, str],
    log: Path,
    request: dict[str, Any],
    undisturbed: list[dict[str, Any]],
    word: str,
    start: Callable[[], None],
    end: Callable[[], None],
    after: int = 1,
) -> None:
    """Start the service (token "t"), send `request`, and once `after` generations are committed
    `start()` the fault. `/healthz` (with the token) must answer 503 naming it (`word`), say no
    reason to a caller without the token, the run's `problem` must name it, and the log say it a
    few times in 3 s, not twice a second; then `end()` it, and the run must complete with the
    `undisturbed` curve, every individual stored once and none pending."""
    local = start_service(env, log)
    client = httpx.Client(base_url=local.url, timeout=30)
    try:
        run_id = client.post("/runs", json=request, headers=AUTH).json()["id"]
        deadline = time.monotonic() + 60
        while client.get(f"/runs/{run_id}").json()["progress"]["generation"] < after:
            assert time.monotonic() < deadline
            time.sleep(0.1)
        start()
        started = time.monotonic()
        while True:
            health = client.get("/healthz", headers=AUTH)
            if health.status_code == 503 and word in health.json()["database"]:
                break
            run = client.get(f"/runs/{run_id}").json()
            assert run["status"] == "running", f"the run ended {run['status']} under the fault"
            assert time.monotonic() - started < 60, health.text
            time.sleep(0.2)
        print(
            f"[{word}] /healthz said {health.json()['database']!r} "
            f"{time.monotonic() - started:.2f} s after the fault began"
        )
        assert client.get("/healthz").json()["database"] == "cannot write"  # no reason to anyone
        problem = client.get(f"/runs/{run_id}").json()["problem"]
        assert problem and word in problem, problem
        time.sleep(3.0)  # a few seconds of the fault: what the log says of them
        said = local.tail(200_000).count("cannot write to the database")
        assert 1 <= said <= 4, local.tail()
        end()
        ended = time.monotonic()
        run = client.get(f"/runs/{run_id}").json()
        while run["status"] != "completed":
            assert time.monotonic() - ended < 120 and run["status"] == "running", run
            time.sleep(0.2)
            run = client.get(f"/runs/{run_id}").json()
        print(f"[{word}] the fault over, the run completed {time.monotonic() - ended:.2f} s after")
        assert client.get(f"/runs/{run_id}/curve").json()["generations"] == undisturbed
        assert client.get("/healthz").json()["status"] == "ok" and run["problem"] is None
        items = client.get(f"/runs/{run_id}/individuals", params={"limit": 5000}).json()
        assert items["total"] == request["population"] * request["generations"]
        assert all(item["status"] != "pending" for item in items["items"])
    finally:
        client.close()
        local.stop()
