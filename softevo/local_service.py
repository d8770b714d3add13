"""A `softevo serve` child process, started and waited for in one place: `softevo reproduce`
starts its private service with it, and so do the tests and the benches.

The child is started with `python -P`, so the current directory is not first on its path and a
folder there named `softevo` (a clone, say) cannot stand in for the installed package."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Self

import httpx


class ServiceError(RuntimeError):
    """The service exited or did not answer in time; the message ends with its log's tail."""


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on now."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


class LocalService:
    """One `softevo serve` on a free port of 127.0.0.1, its output in `log`."""

    def __init__(
        self, env: Mapping[str, str], log: Path, *args: str, cwd: Path | None = None
    ) -> None:
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.log = log
        command = [sys.executable, "-P", "-m", "softevo.cli", "serve", "--port", str(self.port)]
        with log.open("wb") as out:
            self.process = subprocess.Popen(
                [*command, *args], env=dict(env), cwd=cwd, stdout=out, stderr=subprocess.STDOUT
            )

    def tail(self, characters: int = 4000) -> str:
        return self.log.read_text(errors="replace")[-characters:]

    def wait_ready(self, timeout: float = 60.0) -> Self:
        """Until /healthz answers 200; ServiceError if the process exits or time runs out."""
        deadline = time.monotonic() + timeout
        while True:
            if self.process.poll() is not None:
                raise ServiceError(
                    f"softevo serve exited with {self.process.returncode}:\n{self.tail()}"
                )
            with contextlib.suppress(httpx.TransportError):
                if httpx.get(f"{self.url}/healthz", timeout=2).status_code == 200:
                    return self
            if time.monotonic() > deadline:
                self.stop()
                raise ServiceError(f"softevo serve did not answer in {timeout:g} s:\n{self.tail()}")
            time.sleep(0.1)

    def stop(self, timeout: float = 30.0) -> None:
        """A graceful shutdown (runs handed back at once), killed if it takes too long."""
        if self.process.poll() is None:
            self.process.terminate()
        try:
            self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()

    def kill(self) -> None:
        """SIGKILL, as a crash would."""
        if self.process.poll() is None:
            os.kill(self.process.pid, signal.SIGKILL)
        self.process.wait(timeout=10)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def start_service(
    env: Mapping[str, str],
    log: Path,
    *args: str,
    cwd: Path | None = None,
    timeout: float = 60.0,
) -> LocalService:
    """Start `softevo serve ARGS` with exactly `env` and return it once /healthz answers."""
    return LocalService(env, log, *args, cwd=cwd).wait_ready(timeout)


def service_env(**settings: str) -> dict[str, str]:
    """This process's environment without any `SOFTEVO_*` setting, plus `settings`
    (`database_url="..."` becomes SOFTEVO_DATABASE_URL)."""
    env = {key: value for key, value in os.environ.items() if not key.startswith("SOFTEVO_")}
    env.update({f"SOFTEVO_{key.upper()}": value for key, value in settings.items()})
    return env
