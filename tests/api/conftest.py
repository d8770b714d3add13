"""Fixtures of the service tests: a fresh database on SQLite and on PostgreSQL, and a live app.

PostgreSQL tests create a database of their own on the server at SOFTEVO_TEST_POSTGRES
(default: postgresql://postgres@127.0.0.1:5432/test) and drop it afterwards, or take one of the
test process's migrated databases, emptied after each test (`PostgresDatabases`). Without a server
they skip on a laptop, but under CI=true a missing PostgreSQL fails them.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import create_engine, inspect, text
from sqlalchemy.engine import make_url

from softevo.api.app import create_app
from softevo.api.db import Database, end_sessions, normalise_url, scratch_postgres
from softevo.api.settings import Settings
from softevo.core.physics.evaluation import SerialEvaluator

POSTGRES = os.environ.get("SOFTEVO_TEST_POSTGRES", "postgresql://postgres@127.0.0.1:5432/test")


@contextmanager
def _fresh_postgres(template: str | None = None) -> Iterator[str]:
    """A database of its own on the server at POSTGRES (a copy of `template`, or empty), dropped
    afterwards; without a server a skip, or under CI=true a failure."""
    try:
        scratch = scratch_postgres(POSTGRES, "softevo_test", template)
        url = scratch.__enter__()
    except Exception as error:
        if os.environ.get("CI") == "true":
            pytest.fail(f"PostgreSQL is needed under CI and is not reachable: {error}")
        pytest.skip(f"no PostgreSQL at {POSTGRES}: {type(error).__name__}")
    try:
        yield url
    finally:
        scratch.__exit__(None, None, None)


@pytest.fixture
def postgres_url() -> Iterator[str]:
    """A fresh, empty PostgreSQL database for one test."""
    with _fresh_postgres() as url:
        yield url


class PostgresDatabases:
    """Migrated PostgreSQL databases of this test process, each used by one test at a time and
    emptied between tests. Creating a database costs 0.1 to 0.4 s of the server's fsyncs and
    migrating one 0.2 s; emptying one (every table truncated, every sequence back at 1) costs a
    few milliseconds. All are dropped when the process's tests end."""

    def __init__(self, stack: ExitStack) -> None:
        self.stack = stack
        self.template: str | None = None  # migrated once, then copied
        self.tables = ""  # the template's tables but alembic_version, for TRUNCATE
        self.free: list[str] = []

    def take(self) -> str:
        if self.free:
            return self.free.pop()
        if self.template is None:
            url = self.stack.enter_context(_fresh_postgres())
            database = Database(url)
            database.upgrade()
            self.tables = ", ".join(
                f'"{table}"'
                for table in inspect(database.engine).get_table_names()
                if table != "alembic_version"
            )
            database.dispose()  # a template has no connections
            self.template = make_url(url).database
        return self.stack.enter_context(_fresh_postgres(self.template))

    def give_back(self, url: str) -> None:
        """Ends the test's sessions and empties the database as a new copy would be."""
        engine = create_engine(normalise_url(url), isolation_level="AUTOCOMMIT")
        try:
            with engine.connect() as connection:
                end_sessions(connection, make_url(url).database or "")
                connection.execute(text(f"TRUNCATE {self.tables} RESTART IDENTITY CASCADE"))
        finally:
            engine.dispose()
        self.free.append(url)


@pytest.fixture(scope="session")
def postgres_databases() -> Iterator[PostgresDatabases]:
    with ExitStack() as stack:
        yield PostgresDatabases(stack)


@pytest.fixture(params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def database_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """The storage suite runs on both: a fresh SQLite file, then a PostgreSQL database, already
    migrated and empty (a test marked `empty_database` gets a new one with no tables). Every
    test and app still runs the migrations itself: on a migrated database they find nothing to
    do."""
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'softevo.db'}"
    elif request.node.get_closest_marker("empty_database"):
        yield request.getfixturevalue("postgres_url")
    else:
        databases: PostgresDatabases = request.getfixturevalue("postgres_databases")
        url = databases.take()
        yield url
        databases.give_back(url)


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
