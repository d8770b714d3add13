"""Crash and resume, for real: `softevo serve` is SIGKILLed in the middle of a generation, started
again on the same database (a SQLite file, then PostgreSQL), takes the run over once its lease
expires, and finishes it with exactly the learning curve of an undisturbed in-process run, each
individual stored once.
"""

from __future__ import annotations

import os
import random
import signal
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from sqlalchemy import Engine, create_engine, text

from softevo.api.db import Database, normalise_url
from softevo.core.evolution import CURVE_COLUMNS
from softevo.local_service import LocalService, ServiceError, start_service
from tests.reference import front_points, undisturbed

#: 3x3x3 robots simulated for 10 s: a batch of two takes ~0.1 s, so a generation (about eight new
#: robots, four batches) lasts long enough to be caught between its first and last batch (the
#: watcher looks every 0.02 s and has caught generation 2 after its first batch in every try,
#: as it did with 20 s, which only made the file slower).
REQUEST: dict[str, Any] = {
    "preset": "quick",
    "seed": 7,
    "generations": 6,
    "population": 16,
    "sim": {"duration": 10.0},
}
#: The run of the kills at random moments: its robots simulated for 20 s, so its fixed pauses
#: (0.5 to 2.5 s each) land in the first half of the run, never after its end.
RANDOM_REQUEST: dict[str, Any] = {**REQUEST, "sim": {"duration": 20.0}}
#: The same run as MAP-Elites: its archive rides in the GA state the generation commit writes,
#: over a descriptor of the body and the behavioural `heading` (the headings saved before the
#: kill are read back, not measured again).
QD_REQUEST = {
    **REQUEST,
    "algorithm": "map-elites",
    "descriptors": ["heading", "actuated"],
    "bins": [8, 5],
}
#: The same run as steady-state: births kept as they are bred, rows of 16 births; the births in
#: flight at the kill are bred again by the successor, which finds those saved before it. (It
#: simulates every birth, twice the GA's robots, each as long.)
STEADY_REQUEST = {
    **REQUEST,
    "algorithm": "steady-state",
    "options": {"window": 8},
    "sim": {"duration": 10.0},
}
#: The same run as AFPO on speed and cost of transport: the objective values, births and lineage
#: starts it breeds from, and the front so far, ride in the state the generation commit writes.
AFPO_REQUEST = {
    **REQUEST,
    "algorithm": "afpo",
    "objectives": ["speed", "-cost_of_transport"],
    "options": {"variation": "explore"},  # what a new AFPO run gets (issue 51)
}
GENERATIONS = REQUEST["generations"]
POPULATION = REQUEST["population"]
#: The server is killed in the first generation from KILL_AT on caught half evaluated; the last
#: one is never a target, so the successor always has a whole generation after it to run.
KILL_AT = 2
LEASE_SECONDS = 2.0


class Server:
    """One `softevo serve` process and a client for it; its output goes to a log file."""

    def __init__(self, local: LocalService) -> None:
        self.local = local
        self.process = local.process
        self.client = httpx.Client(base_url=local.url, timeout=10.0)

    def tail(self) -> str:
        return self.local.tail()

    def kill(self) -> None:
        self.local.kill()
        self.client.close()


@pytest.fixture
def engine(database_url: str) -> Iterator[Engine]:
    """The test's database, migrated, for reading what the servers left in it."""
    Database(database_url).upgrade()
    engine = create_engine(normalise_url(database_url))
    yield engine
    engine.dispose()


def serve(database_url: str, log: Path) -> Server:
    """Start `softevo serve` on the database and a free port; return once /healthz says ok."""
    env = {
        **os.environ,
        "SOFTEVO_DATABASE_URL": database_url,
        "SOFTEVO_LEASE_SECONDS": str(LEASE_SECONDS),
        "SOFTEVO_POLL_SECONDS": "0.2",
        "SOFTEVO_WORKERS": "1",
        "SOFTEVO_BATCH_SIZE": "2",
        "SOFTEVO_SAVE_SECONDS": "0",  # every batch saved as it lands: a generation half saved
    }
    try:
        return Server(start_service(env, log))
    except ServiceError as error:
        pytest.fail(str(error))


@pytest.fixture
def start_server(database_url: str, tmp_path: Path) -> Iterator[Callable[[], Server]]:
    """`start_server()`: serve the test's database on a free port; every server dies at the end."""
    servers: list[Server] = []

    def start() -> Server:
        servers.append(serve(database_url, tmp_path / f"server-{len(servers)}.log"))
        return servers[-1]

    try:
        yield start
    finally:
        for server in servers:
            server.kill()


def _individuals(client: httpx.Client, run_id: int, **params: int) -> list[dict[str, Any]]:
    """Every individual (of one generation, if asked), page by page."""
    items: list[dict[str, Any]] = []
    while True:
        page = client.get(
            f"/runs/{run_id}/individuals", params={**params, "offset": len(items), "limit": 25}
        )
        assert page.status_code == 200, page.text
        body = page.json()
        items.extend(body["items"])
        if not body["items"] or len(items) >= body["total"]:
            assert len(items) == body["total"]
            return items


def _mid_generation(client: httpx.Client, run_id: int, generation: int, seen: set[str]) -> bool:
    """`generation` has saved some fitness and still has new genomes (not in `seen`) to evaluate."""
    items = _individuals(client, run_id, generation=generation)
    done = {item["genome_hash"] for item in items if item["status"] in ("evaluated", "failed")}
    todo = {
        item["genome_hash"]
        for item in items
        if item["status"] == "pending" and item["genome_hash"] not in seen | done
    }
    return bool(done) and bool(todo)


def _database_state(engine: Engine, run_id: int) -> dict[str, Any]:
    """The run's status, generations committed, and the generation in progress by status."""
    with engine.connect() as connection:
        status, committed = connection.execute(
            text("SELECT status, generations_done FROM runs WHERE id = :run"), {"run": run_id}
        ).one()
        counts = dict(
            connection.execute(
                text(
                    "SELECT status, count(*) FROM individuals WHERE run_id = :run "
                    "AND generation = :generation GROUP BY status"
                ),
                {"run": run_id, "generation": committed},
            ).all()
        )
    return {"status": status, "committed": committed, "in_progress": counts}


def _saved_fitness(engine: Engine, run_id: int, generation: int) -> list[tuple[Any, ...]]:
    """Fitness saved in `generation` so far: (index, status, fitness, worker, evaluated_at)."""
    with engine.connect() as connection:
        rows = connection.execute(
            text(
                'SELECT "index", status, fitness, worker, evaluated_at FROM individuals '
                "WHERE run_id = :run AND generation = :generation "
                "AND status IN ('evaluated', 'failed') ORDER BY \"index\""
            ),
            {"run": run_id, "generation": generation},
        ).all()
        return [tuple(row) for row in rows]


@pytest.mark.slow
@pytest.mark.fault
#: Each database once and each algorithm once (all four pairs cost the suite 74 s more); the
#: random kills below and the database fault tests cover the rest of the grid.
@pytest.mark.parametrize(
    ("database_url", "request_body"),
    [("sqlite", REQUEST), ("postgres", QD_REQUEST)],
    ids=["sqlite-ga", "postgres-map-elites"],
    indirect=["database_url"],
)
def test_sigkill_mid_generation_then_restart_resumes_with_the_same_curve(
    start_server: Callable[[], Server], engine: Engine, request_body: dict[str, Any]
) -> None:
    database = engine
    first = start_server()
    created = first.client.post("/runs", json=request_body)
    assert created.status_code == 201, created.text
    run_id = created.json()["id"]

    # Watch the run until a generation is half evaluated, then SIGKILL the server.
    seen: dict[int, set[str]] = {}  # generations committed -> genomes of those generations
    deadline = time.monotonic() + 60
    while True:
        assert time.monotonic() < deadline, f"never caught mid-generation:\n{first.tail()}"
        run = first.client.get(f"/runs/{run_id}").json()
        assert run["status"] in ("queued", "running"), run
        committed = run["progress"]["generation"]
        assert committed < GENERATIONS - 1, f"never caught mid-generation:\n{first.tail()}"
        if committed >= KILL_AT:
            if committed not in seen:
                seen[committed] = {
                    item["genome_hash"]
                    for item in _individuals(first.client, run_id)
                    if item["generation"] < committed
                }
            if _mid_generation(first.client, run_id, committed, seen[committed]):
                break
        time.sleep(0.02)
    first.kill()

    killed = _database_state(database, run_id)
    print(f"\nkilled in: {killed}")
    assert killed["status"] == "running"
    assert killed["committed"] == committed, "the kill came after the generation was committed"
    assert killed["in_progress"].get("pending", 0) > 0
    assert killed["in_progress"].get("evaluated", 0) + killed["in_progress"].get("failed", 0) > 0
    saved_before = _saved_fitness(database, run_id, committed)

    # A new server takes the run over once the dead one's lease has expired, and finishes it.
    restarted = time.monotonic()
    second = start_server()
    deadline = restarted + 120
    while True:
        run = second.client.get(f"/runs/{run_id}").json()
        if run["status"] not in ("queued", "running"):
            break
        assert time.monotonic() < deadline, f"run not finished after restart:\n{second.tail()}"
        time.sleep(0.1)
    recovery = time.monotonic() - restarted
    print(f"recovery: run completed {recovery:.2f} s after the restart (lease {LEASE_SECONDS} s)")
    assert run["status"] == "completed", f"{run}\n{second.tail()}"
    assert run["error"] is None
    assert run["takeovers"] >= 1
    assert run["progress"]["generation"] == GENERATIONS

    # Exactly one row per (generation, index), none left pending.
    individuals = _individuals(second.client, run_id)
    assert len(individuals) == GENERATIONS * POPULATION
    assert {(i["generation"], i["index"]) for i in individuals} == {
        (g, i) for g in range(GENERATIONS) for i in range(POPULATION)
    }
    assert all(i["status"] in ("evaluated", "cached", "failed") for i in individuals)
    with engine.connect() as connection:
        duplicates = connection.execute(
            text(
                'SELECT run_id, generation, "index", count(*) FROM individuals '
                'GROUP BY run_id, generation, "index" HAVING count(*) > 1'
            )
        ).all()
        pending = connection.scalar(
            text("SELECT count(*) FROM individuals WHERE status = 'pending'")
        )
        rows = connection.scalar(
            text("SELECT count(*) FROM individuals WHERE run_id = :run"), {"run": run_id}
        )
        generation_rows = connection.execute(
            text("SELECT generation FROM generations WHERE run_id = :run ORDER BY generation"),
            {"run": run_id},
        ).all()
    assert duplicates == []
    assert pending == 0
    assert rows == GENERATIONS * POPULATION
    assert [g for (g,) in generation_rows] == list(range(GENERATIONS))
    # Fitness saved before the crash was kept as it was, not simulated and written again.
    saved_after = {row[0]: row for row in _saved_fitness(database, run_id, committed)}
    assert [saved_after.get(row[0]) for row in saved_before] == saved_before

    # The learning curve is the undisturbed run's, to the last digit.
    curve = second.client.get(f"/runs/{run_id}/curve").json()["generations"]
    evolution = undisturbed(request_body)
    expected = evolution.curve()
    assert len(curve) == len(expected) == GENERATIONS
    assert curve == expected  # every column, coverage and qd_score too for MAP-Elites
    assert run["progress"]["evaluations"] == evolution.evaluations
    assert run["progress"]["saved"] == evolution.saved
    if evolution.state.archive is not None:  # and the archive is the undisturbed run's
        archive = second.client.get(f"/runs/{run_id}/archive").json()
        assert [
            (c["cell"], c["values"], c["fitness"], c["generation"], c["index"])
            for c in archive["cells"]
        ] == [
            (list(e.cell), list(e.values), e.fitness, e.generation, e.index)
            for e in evolution.state.archive.ordered()
        ]
    if "objectives" in request_body:  # and the front is the undisturbed run's
        points = second.client.get(f"/runs/{run_id}/front").json()["points"]
        assert front_points(request_body, points) == evolution.state.data["front"]


@pytest.mark.slow
@pytest.mark.fault
@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_an_afpo_run_with_objectives_sigkilled_resumes_with_the_same_curve_and_front(
    start_server: Callable[[], Server], engine: Engine
) -> None:
    """The test above for AFPO on speed and cost of transport, on SQLite only (its run
    measures energy, so it is the dearest; a takeover of NSGA-II and AFPO on both databases is
    `test_coordinator.py`'s)."""
    test_sigkill_mid_generation_then_restart_resumes_with_the_same_curve(
        start_server, engine, AFPO_REQUEST
    )


@pytest.mark.slow
@pytest.mark.fault
@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)
def test_a_steady_state_run_sigkilled_mid_row_resumes_with_the_same_curve(
    start_server: Callable[[], Server], engine: Engine
) -> None:
    """The test above for steady-state, on SQLite only (a takeover on both databases is
    `test_steady_state.py`'s)."""
    test_sigkill_mid_generation_then_restart_resumes_with_the_same_curve(
        start_server, engine, STEADY_REQUEST
    )


@pytest.mark.slow
@pytest.mark.fault
@pytest.mark.parametrize("database_url", ["sqlite"], indirect=True)  # PostgreSQL: above
def test_sigkill_again_and_again_at_random_moments(
    start_server: Callable[[], Server], engine: Engine
) -> None:
    """Three servers in a row are SIGKILLed at random moments of the run (commits, batches,
    scheduling: wherever the moment falls); after each kill every committed generation is
    whole in the database, and the fourth server finishes the run with the undisturbed curve."""
    rng = random.Random(11)
    server = start_server()
    run_id = server.client.post("/runs", json=RANDOM_REQUEST).json()["id"]
    moments = []
    for _ in range(3):
        time.sleep(rng.uniform(0.5, 2.5))  # the run goes on under the server for this long
        server.kill()
        state = _database_state(engine, run_id)
        moments.append(f"{state['committed']}:{state['in_progress']}")
        with engine.connect() as connection:
            half = connection.execute(
                text(
                    "SELECT i.generation FROM individuals i JOIN runs r ON r.id = i.run_id "
                    "WHERE i.run_id = :run AND i.generation < r.generations_done "
                    "AND i.status = 'pending'"
                ),
                {"run": run_id},
            ).all()
            whole = connection.scalar(
                text("SELECT count(*) FROM generations WHERE run_id = :run"), {"run": run_id}
            )
        assert half == [], f"committed generations with pending individuals: {half}"
        assert whole == state["committed"], "a generation row without its commit"
        server = start_server()
    restarted = time.monotonic()
    deadline = restarted + 120
    while (run := server.client.get(f"/runs/{run_id}").json())["status"] in ("queued", "running"):
        assert time.monotonic() < deadline, f"run not finished:\n{server.tail()}"
        time.sleep(0.1)
    print(
        f"\nkilled at (committed:in progress) {moments}; the last server finished the run "
        f"{time.monotonic() - restarted:.2f} s after it started ({run['takeovers']} takeovers)"
    )
    assert run["status"] == "completed", run
    curve = server.client.get(f"/runs/{run_id}/curve").json()["generations"]
    evolution = undisturbed(RANDOM_REQUEST)
    assert [{c: row[c] for c in CURVE_COLUMNS} for row in curve] == [
        {c: row[c] for c in CURVE_COLUMNS} for row in evolution.curve()
    ]
    individuals = _individuals(server.client, run_id)
    assert sorted((i["generation"], i["index"]) for i in individuals) == [
        (g, i) for g in range(GENERATIONS) for i in range(POPULATION)
    ]
    assert all(i["status"] != "pending" for i in individuals)


#: The generation commit's statements (`Driver._commit`): the cached copies' fitness (an UPDATE of
#: individuals without eval_seconds or worker, unlike a batch's fitness), then the generation row.
IN_COMMIT = text(
    "SELECT query, (SELECT generations_done FROM runs WHERE id = :run) "
    "FROM pg_stat_activity WHERE application_name = :app "
    "AND xact_start IS NOT NULL AND state IN ('active', 'idle in transaction') "
    "AND ((query LIKE 'UPDATE individuals SET fitness%' AND query NOT LIKE '%worker%') "
    "OR query LIKE 'INSERT INTO generations%')"
)


@pytest.mark.slow
@pytest.mark.fault
@pytest.mark.postgres
def test_sigkill_inside_the_generation_commit_transaction(
    postgres_url: str, tmp_path: Path
) -> None:
    """PostgreSQL shows what each connection is doing: the server is SIGKILLed at the moment
    its connection is inside a generation's commit transaction, which must then roll back as a
    whole; a new server finishes the run with the undisturbed curve."""
    Database(postgres_url).upgrade()
    url = f"{postgres_url}?application_name=softevo-crash"
    watch = create_engine(normalise_url(postgres_url), isolation_level="AUTOCOMMIT")
    servers: list[Server] = []
    caught: tuple[int, str] | None = None
    try:
        for attempt in range(5):  # a commit lasts milliseconds: it may slip by; try again
            servers.append(serve(url, tmp_path / f"server-{attempt}.log"))
            server = servers[-1]
            if attempt == 0:
                run_id = server.client.post("/runs", json=REQUEST).json()["id"]
            with watch.connect() as connection:
                deadline = time.monotonic() + 30
                while time.monotonic() < deadline and server.process.poll() is None:
                    row = connection.execute(
                        IN_COMMIT, {"app": "softevo-crash", "run": run_id}
                    ).first()
                    if row is not None:
                        os.kill(server.process.pid, signal.SIGKILL)
                        server.kill()
                        break
                else:
                    pytest.fail(f"no generation commit seen in 30 s:\n{server.tail()}")
                done, generations = connection.execute(
                    text(
                        "SELECT r.generations_done, (SELECT count(*) FROM generations g "
                        "WHERE g.run_id = r.id) FROM runs r WHERE r.id = :run"
                    ),
                    {"run": run_id},
                ).one()
                cached = connection.scalar(
                    text(
                        "SELECT count(*) FROM individuals WHERE run_id = :run "
                        "AND generation = :g AND status = 'cached'"
                    ),
                    {"run": run_id, "g": done},
                )
                upcoming = connection.scalar(
                    text(
                        "SELECT count(*) FROM individuals WHERE run_id = :run AND generation = :n"
                    ),
                    {"run": run_id, "n": done + 1},
                )
            assert done == generations, "the run's counter and its generation rows disagree"
            assert cached == 0, "a rolled-back commit left cached fitness behind"
            assert upcoming == 0, "a rolled-back commit left the next generation's members"
            if done == row[1]:  # the commit seen in flight never landed: it was rolled back
                caught = (done, row[0].split(" SET")[0].split(" (")[0])
                break
        assert caught is not None, "never caught inside a commit in 5 tries"
        final = serve(url, tmp_path / "server-final.log")
        servers.append(final)
        restarted = time.monotonic()
        while (run := final.client.get(f"/runs/{run_id}").json())["status"] in (
            "queued",
            "running",
        ):
            assert time.monotonic() - restarted < 120, f"not finished:\n{final.tail()}"
            time.sleep(0.1)
        print(
            f"\nSIGKILLed inside the commit of generation {caught[0]} ({caught[1]}); rolled "
            f"back whole; the next server finished {time.monotonic() - restarted:.2f} s later"
        )
        assert run["status"] == "completed", run
        curve = final.client.get(f"/runs/{run_id}/curve").json()["generations"]
        evolution = undisturbed(REQUEST)
        assert [{c: row[c] for c in CURVE_COLUMNS} for row in curve] == [
            {c: row[c] for c in CURVE_COLUMNS} for row in evolution.curve()
        ]
        individuals = _individuals(final.client, run_id)
        assert len(individuals) == GENERATIONS * POPULATION
        assert all(i["status"] != "pending" for i in individuals)
    finally:
        for server in servers:
            server.kill()
        watch.dispose()


def _descendants(pid: int) -> set[int]:
    """Processes below `pid`: its children, theirs, and so on (from /proc)."""
    parents: dict[int, int] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            parents[int(stat.parent.name)] = int(stat.read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
    found, frontier = set(), {pid}
    while frontier:
        frontier = {child for child, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return found


def _alive(pid: int) -> bool:
    """Running, not a zombie waiting for a parent (init here may never reap it)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.slow
@pytest.mark.fault
def test_sigkill_of_the_server_leaves_no_pool_process(tmp_path: Path) -> None:
    """The in-process pool's processes (and multiprocessing's fork server and resource tracker)
    go with the server however it dies: none is left simulating under init."""
    env = {
        **{k: v for k, v in os.environ.items() if not k.startswith("SOFTEVO_")},
        "SOFTEVO_DATABASE_URL": f"sqlite:///{tmp_path / 'softevo.db'}",
        "SOFTEVO_WORKERS": "2",
    }
    local = start_service(env, tmp_path / "server.log")
    try:
        with httpx.Client(base_url=local.url, timeout=30) as client:
            run = client.post("/runs", json={**REQUEST, "generations": 2}).json()["id"]
            deadline = time.monotonic() + 120
            while client.get(f"/runs/{run}").json()["status"] != "completed":
                assert time.monotonic() < deadline, local.tail()
                time.sleep(0.1)
        children = _descendants(local.process.pid)
        # the pool's two processes at least, and the fork server they are forked from
        assert len(children) >= 3, children
        local.kill()
        killed = time.monotonic()
        while any(_alive(pid) for pid in children):
            assert time.monotonic() - killed < 15, [p for p in children if _alive(p)]
            time.sleep(0.1)
        print(
            f"[h] {len(children)} children of the SIGKILLed server gone "
            f"{time.monotonic() - killed:.2f} s after"
        )
    finally:
        local.stop()
