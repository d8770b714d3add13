"""PostgreSQL faults, done for real while a run goes: its connections terminated by the server
(`pg_terminate_backend`) again and again, commits included, and the database host cut off
altogether behind a TCP relay. A generation is never half written, the API answers 503 JSON
while the database is away and recovers by itself, and the run ends with the undisturbed curve,
each individual stored once.
"""

from __future__ import annotations

import random
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

from softevo.api.app import create_app
from softevo.api.db import Database
from softevo.api.settings import Settings
from softevo.core.config import resolve
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.evolution import CURVE_COLUMNS, Evolution
from tests.services import PostgresServer, TcpProxy

pytestmark = [pytest.mark.postgres, pytest.mark.slow, pytest.mark.fault]

#: 3x3x3 robots for 30 s simulated: ~0.1 s each, so the run lasts several seconds in process.
REQUEST: dict[str, Any] = {
    "preset": "quick",
    "seed": 5,
    "population": 10,
    "generations": 8,
    "sim": {"duration": 30.0},
}
LEASE_SECONDS = 2.0


@pytest.fixture(scope="module")
def undisturbed() -> list[dict[str, Any]]:
    evolution = Evolution.start(resolve(REQUEST))
    evolution.run(SerialEvaluator())
    return evolution.curve()


def make_client(url: str) -> TestClient:
    settings = Settings(database_url=url, poll_seconds=0.1, lease_seconds=LEASE_SECONDS)
    return TestClient(create_app(settings, lambda _s: SerialEvaluator()))


HALF_WRITTEN = text(
    "SELECT g.generation FROM generations g JOIN individuals i "
    "ON i.run_id = g.run_id AND i.generation = g.generation "
    "WHERE g.run_id = :run GROUP BY g.generation "
    "HAVING count(*) <> :population OR sum(CASE WHEN i.status = 'pending' THEN 1 ELSE 0 END) > 0"
)


class Watcher:
    """Checks, over its own connection, that every committed generation is whole."""

    def __init__(self, url: str, run_id: int) -> None:
        self.engine = create_engine(
            url.replace("postgresql://", "postgresql+psycopg://", 1), pool_pre_ping=True
        )
        self.run_id = run_id
        self.checks = 0

    def check(self) -> None:
        params = {"run": self.run_id, "population": REQUEST["population"]}
        with self.engine.connect() as connection:
            broken = connection.execute(HALF_WRITTEN, params).scalars().all()
        assert broken == [], f"generations committed half written: {broken}"
        self.checks += 1


def wait_done(client: TestClient, run_id: int, timeout: float, watcher: Watcher) -> dict:
    deadline = time.monotonic() + timeout
    while True:
        response = client.get(f"/runs/{run_id}")
        if response.status_code == 200 and response.json()["status"] not in ("queued", "running"):
            return response.json()
        assert time.monotonic() < deadline, f"run not done in {timeout:.0f} s: {response.text}"
        watcher.check()
        time.sleep(0.1)


def check_completed(client: TestClient, run: dict, undisturbed: list[dict[str, Any]]) -> None:
    assert run["status"] == "completed", run
    items = client.get(f"/runs/{run['id']}/individuals", params={"limit": 5000}).json()["items"]
    keys = sorted((i["generation"], i["index"]) for i in items)
    assert keys == [
        (g, i) for g in range(REQUEST["generations"]) for i in range(REQUEST["population"])
    ]
    assert all(i["status"] != "pending" for i in items)
    curve = client.get(f"/runs/{run['id']}/curve").json()["generations"]
    assert [{c: row[c] for c in CURVE_COLUMNS} for row in curve] == [
        {c: row[c] for c in CURVE_COLUMNS} for row in undisturbed
    ]


def check_unavailable(client: TestClient, run_id: int) -> int:
    """While the database is away: reads and writes alike answer 503 JSON, no trace."""
    answers = [client.get(path) for path in (f"/runs/{run_id}", "/healthz", "/runs")]
    answers.append(client.post("/runs", json=REQUEST))
    answers.append(client.post(f"/runs/{run_id}/cancel"))
    for response in answers:
        assert response.status_code == 503, (response.request.url, response.text)
        assert response.headers["content-type"] == "application/json"
        assert "Traceback" not in response.text
        body = response.json()
        assert body.get("detail") or body.get("database", "").startswith("down"), body
    return len(answers)


@pytest.fixture
def database(postgres_url: str) -> Iterator[str]:
    db = Database(postgres_url)
    db.upgrade()
    db.dispose()
    yield postgres_url


def test_connections_terminated_again_and_again_during_commits(
    database: str, undisturbed: list[dict[str, Any]]
) -> None:
    admin = create_engine(
        database.replace("postgresql://", "postgresql+psycopg://", 1), isolation_level="AUTOCOMMIT"
    )
    name = make_url(database).database
    kills: list[int] = []
    stop = threading.Event()

    def terminate() -> None:
        rng = random.Random(7)
        with admin.connect() as connection:
            while not stop.wait(rng.uniform(0.02, 0.3)):
                ended = connection.execute(
                    text(
                        "SELECT count(pg_terminate_backend(pid)) FROM pg_stat_activity "
                        "WHERE datname = :name AND pid <> pg_backend_pid() "
                        "AND application_name <> 'watcher'"
                    ),
                    {"name": name},
                ).scalar_one()
                kills.append(int(ended))

    started = time.monotonic()
    with make_client(database) as client:
        run_id = client.post("/runs", json=REQUEST).json()["id"]
        watcher = Watcher(database + "?application_name=watcher", run_id)
        killer = threading.Thread(target=terminate, daemon=True)
        killer.start()
        while time.monotonic() - started < 6.0:  # several generations' worth of terminations
            watcher.check()
            time.sleep(0.1)
        stop.set()
        killer.join(5)
        stopped = time.monotonic()
        run = wait_done(client, run_id, timeout=90, watcher=watcher)
        print(
            f"\n[pg] {len(kills)} rounds of pg_terminate_backend ended {sum(kills)} connections "
            f"in 6 s; the run completed {time.monotonic() - stopped:.2f} s after they stopped "
            f"({time.monotonic() - started:.2f} s in all, {run['takeovers']} takeovers, "
            f"{watcher.checks} whole-generation checks)"
        )
        assert sum(kills) > 0, "no connection was ever terminated: the fault did not happen"
        check_completed(client, run, undisturbed)
    admin.dispose()
    watcher.engine.dispose()


def ride_out(
    client: TestClient,
    watched: str,
    undisturbed: list[dict[str, Any]],
    down: Callable[[], None],
    up: Callable[[], None],
    watch_while_down: bool = True,
) -> str:
    """Start a run; once a generation is committed take the database `down` for 3 s (every
    answer meanwhile 503 JSON, writes included), bring it `up`; the API must recover by itself
    and the run complete with the undisturbed curve. `watched` is where the watcher checks that
    no generation is half written (while down too, if it can reach it). What happened, in words."""
    run_id = client.post("/runs", json=REQUEST).json()["id"]
    watcher = Watcher(watched, run_id)
    deadline = time.monotonic() + 30
    while client.get(f"/runs/{run_id}").json()["progress"]["generation"] < 1:
        assert time.monotonic() < deadline, "no generation committed before the fault"
        time.sleep(0.05)
    down()
    went = time.monotonic()
    answers = 0
    while time.monotonic() - went < 3.0:
        answers += check_unavailable(client, run_id)
        if watch_while_down:
            watcher.check()
        time.sleep(0.2)
    up()
    back = time.monotonic()
    while client.get("/healthz").status_code != 200:
        assert time.monotonic() - back < 10, "the API did not recover by itself"
        time.sleep(0.05)
    answering = time.monotonic() - back
    run = wait_done(client, run_id, timeout=90, watcher=watcher)
    check_completed(client, run, undisturbed)
    watcher.engine.dispose()
    return (
        f"away for {back - went:.2f} s ({answers} answers, all 503 JSON); the API answered again "
        f"{answering:.2f} s after it came back, and the run completed "
        f"{time.monotonic() - back:.2f} s after ({run['takeovers']} takeovers)"
    )


def test_database_host_cut_off_then_back(database: str, undisturbed: list[dict[str, Any]]) -> None:
    url = make_url(database)
    proxy = TcpProxy((url.host or "127.0.0.1", url.port or 5432))
    through = url.set(host="127.0.0.1", port=proxy.port).render_as_string(False)
    with make_client(through) as client:
        said = ride_out(client, database, undisturbed, proxy.down, proxy.up)
    proxy.down()
    print(f"\n[pg] database host cut off: {said}")


@pytest.fixture
def own_postgres() -> Iterator[PostgresServer]:
    """A PostgreSQL server of the test's own, so it can be crashed and restarted for real."""
    server = PostgresServer()
    try:
        Database(server.url).upgrade()
        yield server
    finally:
        server.stop()


def test_postgres_server_crashed_and_restarted(
    own_postgres: PostgresServer, undisturbed: list[dict[str, Any]]
) -> None:
    """The server itself goes: `pg_ctl stop -m immediate` (every backend killed, no checkpoint)
    in the middle of the run, three seconds down, then started again, crash recovery and all.
    The watcher's connection goes with the server, and checks again once it is back."""
    with make_client(own_postgres.url) as client:
        said = ride_out(
            client, own_postgres.url, undisturbed, own_postgres.crash, own_postgres.start, False
        )
    print(f"\n[pg] PostgreSQL crashed (immediate stop): {said}")


def test_a_database_that_turns_read_only_is_said_and_the_run_goes_on_after(
    database: str, undisturbed: list[dict[str, Any]], tmp_path: Any
) -> None:
    """PostgreSQL made read-only under a running `softevo serve`: `/healthz` (with the token)
    and the run say why nothing moves, the log says it a few times, not twice a second with
    tracebacks; writable again, the run completes with the undisturbed curve."""
    from softevo.local_service import service_env
    from tests.api.said import said_and_survived

    admin = create_engine(
        database.replace("postgresql://", "postgresql+psycopg://", 1), isolation_level="AUTOCOMMIT"
    )
    name = make_url(database).database

    def read_only(on: bool) -> None:
        with admin.connect() as connection:
            value = "on" if on else "off"
            connection.execute(
                text(f'ALTER DATABASE "{name}" SET default_transaction_read_only = {value}')
            )
            connection.execute(
                text(
                    "SELECT pg_terminate_backend(pid) FROM pg_stat_activity "
                    "WHERE datname = :name AND pid <> pg_backend_pid()"
                ),
                {"name": name},
            )

    env = service_env(
        database_url=database,
        api_token="t",
        workers="1",
        poll_seconds="0.2",
        lease_seconds=str(LEASE_SECONDS),
    )
    said_and_survived(
        env,
        tmp_path / "serve.log",
        REQUEST,
        undisturbed,
        "read-only",
        lambda: read_only(True),
        lambda: read_only(False),
    )
    admin.dispose()
