"""Real services for tests: a private redis-server on a free port, and `softevo worker`
processes. Without the binary the tests skip on a laptop, but under CI=true they fail."""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import pytest

from softevo.local_service import free_port


def require(binary: str) -> str:
    path = shutil.which(binary)
    if path is None:
        if os.environ.get("CI") == "true":
            pytest.fail(f"{binary} is needed under CI and is not installed")
        pytest.skip(f"{binary} is not installed")
    return path


ROOT = Path(__file__).resolve().parent.parent


class RedisServer:
    """A redis-server of our own (no persistence), which a test may kill and start again."""

    def __init__(self, workdir: Path) -> None:
        self.binary = require("redis-server")
        self.port = free_port()
        self.workdir = workdir
        self.process: subprocess.Popen[bytes] | None = None

    @property
    def url(self) -> str:
        return f"redis://127.0.0.1:{self.port}/0"

    def start(self) -> None:
        command = [self.binary, "--port", str(self.port), "--bind", "127.0.0.1"]
        command += ["--save", "", "--appendonly", "no", "--dir", str(self.workdir)]
        self.process = subprocess.Popen(
            command,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline:
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.2) as s:
                    s.sendall(b"PING\r\n")
                    if s.recv(16).startswith(b"+PONG"):
                        return
            except OSError:
                time.sleep(0.05)
        raise RuntimeError(f"redis-server did not start on port {self.port}")

    def kill(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.send_signal(signal.SIGKILL)
            self.process.wait(10)


class PostgresServer:
    """A PostgreSQL server of our own (a fresh cluster on a free port, trust auth), which a test
    may crash (`pg_ctl stop -m immediate`: no shutdown checkpoint, like a power cut) and start
    again. The cluster belongs to the `postgres` user when the tests run as root."""

    def __init__(self) -> None:
        bins = sorted(Path("/usr/lib/postgresql").glob("*/bin/initdb"))
        found = str(bins[-1]) if bins else shutil.which("initdb")  # Debian's, with its tools
        if found is None:
            require("initdb")  # fails under CI, skips elsewhere
        self.bin = Path(str(found)).parent
        self.port = free_port()
        # a folder of its own, outside pytest's (which only root may enter)
        self.home = Path(tempfile.mkdtemp(prefix="softevo-pg-"))
        self.data = self.home / "data"
        self.user: list[str] = []
        if os.geteuid() == 0:  # initdb refuses root: run the server as postgres
            self.user = ["runuser", "-u", "postgres", "--"]
            shutil.chown(self.home, "postgres")
        self._run("initdb", "-D", str(self.data), "-A", "trust", "-U", "postgres", "-E", "UTF8")
        self.start()
        self._run("createdb", "-h", "127.0.0.1", "-p", str(self.port), "-U", "postgres", "softevo")

    @property
    def url(self) -> str:
        return f"postgresql://postgres@127.0.0.1:{self.port}/softevo"

    def _run(self, tool: str, *args: str) -> None:
        done = subprocess.run(
            [*self.user, str(self.bin / tool), *args], capture_output=True, text=True, timeout=60
        )
        if done.returncode != 0:
            raise RuntimeError(f"{tool} failed: {done.stdout}{done.stderr}")

    def start(self) -> None:
        options = f"-p {self.port} -k {self.home} -c listen_addresses=127.0.0.1 -c fsync=off"
        log = str(self.home / "postgres.log")
        self._run("pg_ctl", "-D", str(self.data), "-o", options, "-l", log, "-w", "start")

    def crash(self) -> None:
        """Stop at once, as a crash would: clients are cut off, recovery runs at the next start."""
        self._run("pg_ctl", "-D", str(self.data), "-m", "immediate", "-w", "stop")

    def stop(self) -> None:
        """Stop for good and remove the cluster."""
        with contextlib.suppress(RuntimeError, subprocess.TimeoutExpired):
            self._run("pg_ctl", "-D", str(self.data), "-m", "fast", "-w", "stop")
        shutil.rmtree(self.home, ignore_errors=True)


class Workers:
    """`softevo worker` processes on one Redis; each logs to its own file."""

    def __init__(self, redis_url: str, workdir: Path) -> None:
        self.redis_url = redis_url
        self.workdir = workdir
        self.processes: dict[str, subprocess.Popen[bytes]] = {}

    def start(self, name: str, *extra: str) -> subprocess.Popen[bytes]:
        log = (self.workdir / f"worker-{name}.log").open("wb")
        # the repository on the path: the fault tests' own job functions (tests.worker.poison_job)
        env = {**os.environ, "SOFTEVO_REDIS_URL": self.redis_url, "PYTHONPATH": str(ROOT)}
        process = subprocess.Popen(
            [sys.executable, "-P", "-m", "softevo.cli", "worker", "--name", name, *extra],
            env=env,
            stdout=log,
            stderr=subprocess.STDOUT,
        )
        self.processes[name] = process
        return process

    def wait_ready(self, name: str, timeout: float = 60) -> None:
        """Until the worker says its kernels are warm and it takes jobs."""
        log = self.workdir / f"worker-{name}.log"
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if "taking jobs" in log.read_text(errors="replace"):
                return
            if self.processes[name].poll() is not None:
                raise RuntimeError(f"worker {name} exited:\n{self.log(name)}")
            time.sleep(0.05)
        raise RuntimeError(f"worker {name} not ready in {timeout} s:\n{self.log(name)}")

    def log(self, name: str) -> str:
        return (self.workdir / f"worker-{name}.log").read_text(errors="replace")[-4000:]

    def kill(self, name: str, sig: signal.Signals = signal.SIGKILL) -> None:
        process = self.processes[name]
        if process.poll() is None:
            process.send_signal(sig)
            if sig in (signal.SIGKILL, signal.SIGTERM):
                process.wait(10)

    def stop_all(self) -> None:
        for process in self.processes.values():
            if process.poll() is None:
                process.send_signal(signal.SIGCONT)
                process.kill()
                process.wait(10)


@pytest.fixture
def redis_server(tmp_path: Path):  # type: ignore[no-untyped-def]
    server = RedisServer(tmp_path)
    server.start()
    yield server
    server.kill()


@pytest.fixture
def workers(redis_server: RedisServer, tmp_path: Path):  # type: ignore[no-untyped-def]
    pool = Workers(redis_server.url, tmp_path)
    yield pool
    pool.stop_all()


class TcpProxy:
    """A TCP relay to a server (PostgreSQL) that a test can cut: `down()` drops every open
    connection and refuses new ones, as a database host that went away would; `up()` listens
    again on the same port. Real sockets both ways, so the client library meets a real outage."""

    def __init__(self, target: tuple[str, int]) -> None:
        self.target = target
        self.port = free_port()
        self._listener: socket.socket | None = None
        self._open: set[socket.socket] = set()
        self._lock = threading.Lock()
        self.up()

    def up(self) -> None:
        listener = socket.socket()
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listener.bind(("127.0.0.1", self.port))
        listener.listen(64)
        self._listener = listener
        threading.Thread(target=self._accept, args=(listener,), daemon=True).start()

    def down(self) -> None:
        listener, self._listener = self._listener, None
        if listener is not None:
            with contextlib.suppress(OSError):
                listener.shutdown(socket.SHUT_RDWR)
            listener.close()
        with self._lock:
            sockets, self._open = self._open, set()
        for sock in sockets:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            sock.close()

    def _accept(self, listener: socket.socket) -> None:
        while True:
            try:
                client, _ = listener.accept()
            except OSError:
                return  # closed by down()
            try:
                server = socket.create_connection(self.target)
            except OSError:
                client.close()
                continue
            with self._lock:
                self._open.update((client, server))
            for source, sink in ((client, server), (server, client)):
                threading.Thread(target=self._pipe, args=(source, sink), daemon=True).start()

    def _pipe(self, source: socket.socket, sink: socket.socket) -> None:
        try:
            while data := source.recv(65536):
                sink.sendall(data)
        except OSError:
            pass
        finally:
            for sock in (source, sink):
                with contextlib.suppress(OSError):
                    sock.shutdown(socket.SHUT_RDWR)
