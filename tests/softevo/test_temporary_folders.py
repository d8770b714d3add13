"""A stopped `softevo serve` (SIGTERM, Ctrl-C) and a finished `softevo run` leave no
multiprocessing temporary folder (`pymp-*`, where the pool's fork server has its socket) behind
(issue 48): the interpreter's exit handlers, which remove it, run. Each process here gets a
temporary folder of its own (TMPDIR), so others' folders in /tmp do not count."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from softevo.local_service import LocalService, service_env

pytestmark = pytest.mark.slow

TINY = {"preset": "quick", "population": 4, "generations": 2, "sim": {"duration": 1.0}}


def _pymp(folder: Path) -> list[str]:
    return sorted(path.name for path in folder.glob("pymp-*"))


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["SIGTERM", "Ctrl-C"])
def test_a_stopped_server_removes_its_temporary_folder(tmp_path: Path, sig: signal.Signals) -> None:
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    env = service_env(database_url=f"sqlite:///{tmp_path / 'served.db'}", workers="2")
    env["TMPDIR"] = str(temporary)
    local = LocalService(env, tmp_path / "server.log").wait_ready(120)
    try:
        run = httpx.post(f"{local.url}/runs", json=TINY, timeout=10).json()
        deadline = time.monotonic() + 120
        while httpx.get(f"{local.url}/runs/{run['id']}", timeout=5).json()["status"] != "completed":
            assert time.monotonic() < deadline, local.tail()
            time.sleep(0.2)
        assert _pymp(temporary), "the pool made no temporary folder: the test would see nothing"
        local.process.send_signal(sig)
        code = local.process.wait(60)
    finally:
        local.stop()
    # an exit, not a death by the signal (-15); Ctrl-C: 130, or 0 where SIGINT was ignored
    assert code == (143 if sig == signal.SIGTERM else code) and code >= 0, local.tail()
    assert _pymp(temporary) == [], local.tail()


def test_a_finished_run_removes_its_temporary_folder(tmp_path: Path) -> None:
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    small = ["--population", "4", "--generations", "2", "--duration", "1", "--workers", "2"]
    out = ["--out", str(tmp_path / "run")]
    command = [sys.executable, "-P", "-m", "softevo.cli", "run", "--preset", "quick", *small, *out]
    env = {**service_env(), "TMPDIR": str(temporary)}
    done = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert _pymp(temporary) == []


def test_sigterm_is_an_exit_only_while_serving() -> None:
    """The handler is put back: a test (or a caller) running the command in process keeps its
    own SIGTERM disposition."""
    from softevo.service_commands import exit_on_sigterm

    before = signal.getsignal(signal.SIGTERM)
    with exit_on_sigterm(), pytest.raises(SystemExit) as exited:
        signal.raise_signal(signal.SIGTERM)
    assert exited.value.code == 143 and signal.getsignal(signal.SIGTERM) == before
