"""A full disk under a live `softevo serve` on SQLite, for real: the database lives on a small
file system of the test's own (a tmpfs, mounted as root), which is filled to the last byte while
a run goes. `/healthz` (with the token) and the run say why nothing moves, the log says it a few
times, not twice a second; once space is back the run completes with the undisturbed curve,
each individual stored once and none pending."""

from __future__ import annotations

import errno
import os
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from softevo.core.config import resolve
from softevo.core.evaluation import SerialEvaluator
from softevo.core.evolution import Evolution
from softevo.local_service import service_env, start_service

pytestmark = [pytest.mark.slow, pytest.mark.fault]

#: 3x3x3 robots for 20 s simulated: the run lasts long enough to fill the disk under it.
REQUEST: dict[str, Any] = {
    "preset": "quick",
    "seed": 6,
    "population": 10,
    "generations": 40,
    "sim": {"duration": 20.0},
}


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A 16 MiB tmpfs of this test's own; unmounted at the end."""
    mount = tmp_path / "disk"
    mount.mkdir()
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=16m", "tmpfs", str(mount)],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    if done.returncode != 0:
        if os.environ.get("CI") == "true":
            pytest.fail(f"CI runs as root and must mount a tmpfs: {done.stderr.strip()}")
        pytest.skip(f"cannot mount a tmpfs here (root only): {done.stderr.strip()}")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=False)


def fill(folder: Path) -> Path:
    """Write one file until the file system has no byte left; its path."""
    filler = folder / "filler"
    descriptor = os.open(filler, os.O_WRONLY | os.O_CREAT)
    try:
        for size in (1 << 20, 1 << 12, 1):
            try:
                while True:
                    os.write(descriptor, b"\0" * size)
            except OSError as error:
                assert error.errno == errno.ENOSPC, error
    finally:
        os.close(descriptor)
    return filler


def test_a_full_disk_is_said_and_the_run_goes_on_after(small_disk: Path, tmp_path: Path) -> None:
    evolution = Evolution.start(resolve(REQUEST))
    evolution.run(SerialEvaluator())
    undisturbed = evolution.curve()
    env = service_env(
        database_url=f"sqlite:///{small_disk / 'softevo.db'}", api_token="t", workers="1",
        poll_seconds="0.2", lease_seconds="2",
    )  # fmt: skip
    auth = {"Authorization": "Bearer t"}
    with (
        start_service(env, tmp_path / "serve.log") as local,
        httpx.Client(base_url=local.url, timeout=30) as client,
    ):
        run_id = client.post("/runs", json=REQUEST, headers=auth).json()["id"]
        deadline = time.monotonic() + 60
        while client.get(f"/runs/{run_id}").json()["progress"]["generation"] < 2:
            assert time.monotonic() < deadline
            time.sleep(0.1)
        filler = fill(small_disk)
        full_at = time.monotonic()
        while True:
            health = client.get("/healthz", headers=auth)
            if health.status_code == 503 and "full" in health.json()["database"]:
                break
            run = client.get(f"/runs/{run_id}").json()
            assert run["status"] == "running", f"the run ended {run['status']} on a full disk"
            assert time.monotonic() - full_at < 60, health.text
            time.sleep(0.2)
        took = time.monotonic() - full_at
        stalled_at = client.get(f"/runs/{run_id}").json()["progress"]["generation"]
        print(f"[disk] /healthz said {health.json()['database']!r} {took:.2f} s after the disk "
              f"filled (at generation {stalled_at})")  # fmt: skip
        assert client.get("/healthz").json()["database"] == "cannot write"  # no reason to anyone
        problem = client.get(f"/runs/{run_id}").json()["problem"]
        assert problem and "full" in problem, problem
        time.sleep(3.0)  # a few seconds of the fault: what the log says of them
        said = local.tail(200_000).count("cannot write to the database")
        assert 1 <= said <= 4, local.tail()
        filler.unlink()
        freed_at = time.monotonic()
        run = client.get(f"/runs/{run_id}").json()
        while run["status"] != "completed":
            assert time.monotonic() - freed_at < 120 and run["status"] == "running", run
            time.sleep(0.2)
            run = client.get(f"/runs/{run_id}").json()
        print(f"[disk] space back: the run completed {time.monotonic() - freed_at:.2f} s after")
        assert client.get(f"/runs/{run_id}/curve").json()["generations"] == undisturbed
        assert client.get("/healthz").json()["status"] == "ok" and run["problem"] is None
        items = client.get(f"/runs/{run_id}/individuals", params={"limit": 1000}).json()
        assert items["total"] == REQUEST["population"] * REQUEST["generations"]
        assert all(item["status"] != "pending" for item in items["items"])
