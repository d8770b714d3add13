"""A full disk under a live `softevo serve` on SQLite, for real: the database lives on a small
file system of the test's own (a tmpfs, mounted as root), which is filled to the last byte while
a run goes. `/healthz` (with the token) and the run say why nothing moves, the log says it a few
times, not twice a second; once space is back the run completes with the undisturbed curve,
each individual stored once and none pending."""

from __future__ import annotations

import errno
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from softevo.local_service import service_env
from tests.api.said import said_and_survived
from tests.reference import undisturbed

pytestmark = [pytest.mark.slow, pytest.mark.fault]

#: 3x3x3 robots for 20 s simulated: the run lasts long enough to fill the disk under it (the
#: fault begins after generation 2 and is said within a second; 14 generations are left).
REQUEST: dict[str, Any] = {
    "preset": "quick",
    "seed": 6,
    "population": 10,
    "generations": 16,
    "sim": {"duration": 20.0},
}


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A 16 MiB tmpfs of this test's own; unmounted at the end."""
    mount = tmp_path / "disk"
    mount.mkdir()
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=16m", "tmpfs", str(mount)],
        capture_output=True,
        text=True,
        check=False,
    )
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
    reference = undisturbed(REQUEST).curve()
    env = service_env(
        database_url=f"sqlite:///{small_disk / 'softevo.db'}",
        api_token="t",
        workers="1",
        poll_seconds="0.2",
        lease_seconds="2",
    )
    filler: list[Path] = []
    said_and_survived(
        env,
        tmp_path / "serve.log",
        REQUEST,
        reference,
        "full",
        lambda: filler.append(fill(small_disk)),
        lambda: filler.pop().unlink(),
        after=2,
    )
