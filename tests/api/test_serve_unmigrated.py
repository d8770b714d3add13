"""`softevo serve` on a PostgreSQL database that was never migrated: one line that says to run
`softevo db upgrade`, exit 1, before uvicorn starts (its failed start-up printed the lifespan's
42-line traceback first; issue 39)."""

from __future__ import annotations

import socket

import pytest

from tests.softevo.inprocess import softevo


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.mark.postgres
def test_serve_on_an_unmigrated_database_says_so_in_one_line(
    postgres_url: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("SOFTEVO_DATABASE_URL", postgres_url)
    done = softevo("serve", "--port", str(_free_port()))
    assert done.returncode == 1
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "softevo db upgrade" in lines[0], done.stderr
    assert "migration none" in lines[0]
