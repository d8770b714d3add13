"""Fixtures of the service tests: a fresh database on SQLite and on PostgreSQL, and a live app.

PostgreSQL tests create a database of their own on the server at SOFTEVO_TEST_POSTGRES
(default: postgresql://postgres@127.0.0.1:5432/test) and drop it afterwards. Without a server
they skip on a laptop, but under CI=true a missing PostgreSQL fails them.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from softevo.api.app import create_app
from softevo.api.db import Database, scratch_postgres
from softevo.api.settings import Settings
from softevo.core.evaluation import SerialEvaluator

POSTGRES = os.environ.get("SOFTEVO_TEST_POSTGRES", "postgresql://postgres@127.0.0.1:5432/test")


@pytest.fixture
def postgres_url() -> Iterator[str]:
    """A fresh, empty PostgreSQL database for one test."""
    try:
        scratch = scratch_postgres(POSTGRES, "softevo_test")
        url = scratch.__enter__()
    except Exception as error:
        if os.environ.get("CI") == "true":
            pytest.fail(f"PostgreSQL is needed under CI and is not reachable: {error}")
        pytest.skip(f"no PostgreSQL at {POSTGRES}: {type(error).__name__}")
    try:
        yield url
    finally:
        scratch.__exit__(None, None, None)


@pytest.fixture(params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def database_url(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """The storage suite runs on both: a SQLite file, then a fresh PostgreSQL database."""
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'softevo.db'}"
    return request.getfixturevalue("postgres_url")


@pytest.fixture
def db(database_url: str) -> Iterator[Database]:
    database = Database(database_url)
    database.upgrade()
    yield database
    database.dispose()


@pytest.fixture
def make_client(database_url: str) -> Iterator[Callable[..., TestClient]]:
    """`make_client(**settings)`: a started app (coordinator running) on the test database."""
    clients: list[TestClient] = []

    def make(**overrides: object) -> TestClient:
        Database(database_url).upgrade()
        settings = Settings(
            database_url=database_url, poll_seconds=0.05, lease_seconds=5.0, **overrides
        )
        client = TestClient(create_app(settings, lambda _s: SerialEvaluator()))
        client.__enter__()
        clients.append(client)
        return client

    yield make
    for client in clients:
        client.__exit__(None, None, None)


@pytest.fixture
def client(make_client: Callable[..., TestClient]) -> TestClient:
    return make_client()
