"""Connection deadlines of a real `softevo serve`: a request head that trickles in is cut off after
SOFTEVO_HEADER_SECONDS, an idle keep-alive connection after SOFTEVO_KEEP_ALIVE_SECONDS, while a
head that arrives in pieces in time, a slow body and everyone else are served as usual."""

from __future__ import annotations

import socket
import time
from collections.abc import Iterator

import httpx
import pytest

from softevo.api.settings import Settings
from softevo.local_service import LocalService, service_env, start_service

HEADER_SECONDS = 1.0
KEEP_ALIVE_SECONDS = 1.0


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LocalService]:
    folder = tmp_path_factory.mktemp("server")
    env = service_env(
        database_url=f"sqlite:///{folder / 'server.db'}",
        workers="1",
        header_seconds=str(HEADER_SECONDS),
        keep_alive_seconds=str(KEEP_ALIVE_SECONDS),
    )
    with start_service(env, folder / "serve.log") as local:
        yield local


def connect(service: LocalService) -> socket.socket:
    return socket.create_connection(("127.0.0.1", service.port), timeout=10)


def closed_after(sock: socket.socket, trickle: bytes = b"", every: float = 0.2) -> float:
    """Send `trickle` a byte at a time, `every` seconds apart, until the server closes the
    connection; the seconds it took (10 s of socket timeout if it never does)."""
    started = time.monotonic()
    sock.settimeout(every)
    sent = 0
    while time.monotonic() - started < 10:
        try:
            if sock.recv(4096) == b"":
                return time.monotonic() - started
        except TimeoutError:
            pass
        except ConnectionResetError:
            return time.monotonic() - started
        if trickle:
            try:
                sock.sendall(trickle[sent % len(trickle) : sent % len(trickle) + 1])
            except (BrokenPipeError, ConnectionResetError):
                return time.monotonic() - started
            sent += 1
    return time.monotonic() - started


def read_response(sock: socket.socket) -> bytes:
    """Read until the end of one response with a Content-Length."""
    data = b""
    sock.settimeout(10)
    while b"\r\n\r\n" not in data:
        data += sock.recv(4096)
    head, _, body = data.partition(b"\r\n\r\n")
    length = next(
        int(line.split(b":", 1)[1])
        for line in head.split(b"\r\n")
        if line.lower().startswith(b"content-length:")
    )
    while len(body) < length:
        body += sock.recv(4096)
    return head


@pytest.mark.fault
def test_a_head_that_trickles_in_is_cut_off(service: LocalService) -> None:
    """A slowloris client: the request line and then a header byte every 0.2 s, forever."""
    with connect(service) as sock:
        sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n")
        took = closed_after(sock, trickle=b"X-Slow: aaaaaaaa")
    print(f"[head] a trickled head was closed after {took:.2f} s (deadline {HEADER_SECONDS} s)")
    assert HEADER_SECONDS * 0.8 <= took < HEADER_SECONDS + 3


def test_many_silent_connections_are_closed_and_others_served(service: LocalService) -> None:
    """Two hundred connections that open and send nothing hold no socket past the deadline, and
    /healthz answers while they are open."""
    sockets = [connect(service) for _ in range(200)]
    try:
        assert httpx.get(f"{service.url}/healthz", timeout=5).status_code == 200
        time.sleep(HEADER_SECONDS + 1.5)
        still_open = 0
        for sock in sockets:
            sock.settimeout(0.5)
            try:
                still_open += sock.recv(1) != b""
            except TimeoutError:
                still_open += 1
            except ConnectionResetError:
                pass
        assert still_open == 0
    finally:
        for sock in sockets:
            sock.close()


def test_a_head_in_pieces_within_the_deadline_is_served(service: LocalService) -> None:
    with connect(service) as sock:
        for piece in (b"GET /healthz HTTP/1.1\r\n", b"Host: x\r\n", b"Accept: */*\r\n", b"\r\n"):
            sock.sendall(piece)
            time.sleep(HEADER_SECONDS / 5)
        assert read_response(sock).startswith(b"HTTP/1.1 200")


def test_the_deadline_is_for_the_head_not_a_slow_body(service: LocalService) -> None:
    """The head arrives at once, its body over twice the header deadline: answered (422 for a
    preset that does not exist, naming it), not cut off."""
    body = b'{"preset": "no-such-preset"}'
    with connect(service) as sock:
        sock.sendall(
            b"POST /runs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
            b"Content-Length: " + str(len(body)).encode() + b"\r\n\r\n"
        )
        for start in range(0, len(body), 4):
            sock.sendall(body[start : start + 4])
            time.sleep(2.5 * HEADER_SECONDS / (len(body) / 4))
        assert read_response(sock).startswith(b"HTTP/1.1 422")


@pytest.mark.fault
def test_an_idle_keep_alive_connection_is_closed_and_a_busy_one_kept(
    service: LocalService,
) -> None:
    with connect(service) as sock:
        for _ in range(3):  # requests closer together than either deadline: one connection
            sock.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
            assert read_response(sock).startswith(b"HTTP/1.1 200")
            time.sleep(KEEP_ALIVE_SECONDS / 2)
        took = closed_after(sock)
    print(f"[keep-alive] an idle connection was closed after {took:.2f} s more")
    assert took < KEEP_ALIVE_SECONDS + 3


@pytest.mark.parametrize("name", ["SOFTEVO_HEADER_SECONDS", "SOFTEVO_KEEP_ALIVE_SECONDS"])
def test_a_deadline_must_be_a_positive_number(name: str) -> None:
    for bad in ("0", "-1", "nan", "inf"):
        with pytest.raises(ValueError, match=name):
            Settings.from_env({name: bad})
    assert Settings.from_env({name: "2.5"}) != Settings()


def test_the_save_interval_must_be_a_number_not_below_zero() -> None:
    for bad in ("-0.5", "nan", "inf"):
        with pytest.raises(ValueError, match="SOFTEVO_SAVE_SECONDS"):
            Settings.from_env({"SOFTEVO_SAVE_SECONDS": bad})
    assert Settings.from_env({"SOFTEVO_SAVE_SECONDS": "0"}).save_seconds == 0
