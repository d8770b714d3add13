"""API latency benchmark: `python bench/api_latency.py [--skip-postgres] [--postgres URL]
[--requests N]`.

For each database (a SQLite file, then a fresh PostgreSQL database created on the server at
--postgres and dropped afterwards), starts the service as `softevo serve` in a subprocess on a free
port (its coordinator and its in-process pool of one process per core), queues one `quick` run of
100 generations x 25 robots (0.6 s simulations) with `POST /runs` and waits for it to complete,
printing how long that took; then times, over HTTP with httpx on one keep-alive connection, N
sequential requests (after 20 to warm up) of each read endpoint of that finished run:

* `GET /runs/{id}/curve`: the learning curve, 100 rows;
* `GET /runs/{id}/individuals?generation=g&limit=1000`: one generation's 25 individuals (g cycles
  through the 100 generations);
* `GET /runs/{id}/individuals?limit=1000`: the first page of 1000 of the run's 2500 individuals.

Latencies are client-side wall times per request (send to last byte read), p50 and p99 in ms.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import numpy as np
from benchlib import cpu_model
from sqlalchemy import create_engine, text
from sqlalchemy.engine import make_url

from softevo.api.db import Database, normalise_url, scratch_postgres
from softevo.local_service import service_env, start_service

DEFAULT_POSTGRES = os.environ.get(
    "SOFTEVO_TEST_POSTGRES", "postgresql://postgres@127.0.0.1:5432/test"
)
GENERATIONS, POPULATION = 100, 25
RUN = {
    "preset": "quick",
    "seed": 1,
    "generations": GENERATIONS,
    "population": POPULATION,
    "sim": {"duration": 0.6, "settle_time": 0.1},
}


def postgres_unreachable(server_url: str) -> str | None:
    """Why the server cannot be used, or None."""
    try:
        engine = create_engine(normalise_url(server_url))
        with engine.connect() as connection:
            connection.execute(text("SELECT 1"))
        engine.dispose()
    except Exception as error:
        return f"{type(error).__name__}: {str(error).splitlines()[0] if str(error) else ''}"
    return None


@contextlib.contextmanager
def postgres_database(server_url: str) -> Iterator[str]:
    """A fresh database `softevo_bench_<random>` on the server, migrated; dropped afterwards."""
    with scratch_postgres(server_url, "softevo_bench") as url:
        db = Database(url)
        db.upgrade()  # `softevo serve` refuses a PostgreSQL database that is not migrated
        db.dispose()
        yield url


@contextlib.contextmanager
def serve(database_url: str, workdir: Path) -> Iterator[str]:
    """`softevo serve` on a free port with this database; yields its base URL."""
    # The default settings (no token, one pool process per core), whatever this shell sets.
    env = service_env(database_url=database_url)
    log = workdir / f"serve-{database_url.split(':')[0]}.log"
    with start_service(env, log, "--log-level", "warning", cwd=workdir) as local:
        yield local.url  # stopped gracefully after: the run's lease is handed back


def run_to_completion(client: httpx.Client) -> tuple[int, float, dict]:
    started = time.perf_counter()
    created = client.post("/runs", json=RUN)
    created.raise_for_status()
    run_id = created.json()["id"]
    deadline = time.monotonic() + 600
    while True:
        run = client.get(f"/runs/{run_id}").json()
        if run["status"] not in ("queued", "running"):
            break
        if time.monotonic() > deadline:
            raise RuntimeError(f"run {run_id} did not finish in 600 s: {run['progress']}")
        time.sleep(0.1)
    wall = time.perf_counter() - started
    if run["status"] != "completed":
        raise RuntimeError(f"run {run_id} ended {run['status']}: {run['error']}")
    return run_id, wall, run


def latency(
    client: httpx.Client, path: Callable[[int], str], requests: int, warmup: int
) -> tuple[float, float, int]:
    """p50 and p99 (ms) of `requests` sequential GETs after `warmup`, and the body size."""
    for i in range(warmup):
        client.get(path(i)).raise_for_status()
    times, size = [], 0
    for i in range(requests):
        started = time.perf_counter()
        response = client.get(path(i))
        body = response.content
        times.append(time.perf_counter() - started)
        response.raise_for_status()
        size = max(size, len(body))
    p50, p99 = np.percentile(np.array(times) * 1000, [50, 99])
    return float(p50), float(p99), size


def bench_backend(
    name: str, database_url: str, workdir: Path, requests: int, warmup: int
) -> list[tuple[str, str, float, float, int]]:
    rows = []
    with serve(database_url, workdir) as base, httpx.Client(base_url=base, timeout=60) as client:
        run_id, wall, run = run_to_completion(client)
        progress = run["progress"]
        simulations = progress["evaluations"]
        print(
            f"{name:<12}{wall:>8.1f} s   {progress['generation']} generations, "
            f"{simulations} simulations ({simulations / wall:.0f}/s over the wall time), "
            f"{progress['saved']} from the cache"
        )
        curve = client.get(f"/runs/{run_id}/curve").json()
        one = client.get(f"/runs/{run_id}/individuals?generation=0&limit=1000").json()
        page = client.get(f"/runs/{run_id}/individuals?limit=1000").json()
        assert len(curve["generations"]) == GENERATIONS, len(curve["generations"])
        assert len(one["items"]) == POPULATION, len(one["items"])
        assert len(page["items"]) == 1000 and page["total"] == GENERATIONS * POPULATION
        endpoints: list[tuple[str, Callable[[int], str]]] = [
            ("curve (100 rows)", lambda _i: f"/runs/{run_id}/curve"),
            (
                "individuals, 1 generation (25)",
                lambda i: f"/runs/{run_id}/individuals?generation={i % GENERATIONS}&limit=1000",
            ),
            ("individuals, limit=1000", lambda _i: f"/runs/{run_id}/individuals?limit=1000"),
        ]
        for label, path in endpoints:
            p50, p99, size = latency(client, path, requests, warmup)
            rows.append((name, label, p50, p99, size))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--postgres",
        default=DEFAULT_POSTGRES,
        metavar="URL",
        help=f"server to create a scratch PostgreSQL database on ({DEFAULT_POSTGRES})",
    )
    parser.add_argument("--skip-postgres", action="store_true", help="SQLite only")
    parser.add_argument("--requests", type=int, default=200, help="timed requests per endpoint")
    parser.add_argument("--warmup", type=int, default=20, help="untimed requests first")
    args = parser.parse_args()

    print(f"machine: {os.cpu_count()} cores, {cpu_model()}, Python {platform.python_version()}")
    print(
        f"run: quick preset, {GENERATIONS} generations x {POPULATION} robots, 0.6 s simulations, "
        "softevo serve (in-process pool, one process per core)"
    )
    print(
        f"latency: {args.requests} sequential requests per endpoint after {args.warmup} "
        "to warm up, one keep-alive connection\n"
    )
    print(f"{'database':<12}{'run wall time':>13}")
    rows = []
    with tempfile.TemporaryDirectory(prefix="softevo-bench-api-") as tmp:
        workdir = Path(tmp)
        rows += bench_backend(
            "SQLite", f"sqlite:///{workdir / 'bench.db'}", workdir, args.requests, args.warmup
        )
        why = None if args.skip_postgres else postgres_unreachable(args.postgres)
        if why is not None:
            shown = make_url(normalise_url(args.postgres)).render_as_string(hide_password=True)
            print(f"PostgreSQL   skipped: {shown} unreachable ({why}); --skip-postgres to omit it")
        elif not args.skip_postgres:
            with postgres_database(args.postgres) as url:
                rows += bench_backend("PostgreSQL", url, workdir, args.requests, args.warmup)

    print(f"\n{'database':<12}{'endpoint':<34}{'p50 (ms)':>10}{'p99 (ms)':>10}{'body (KiB)':>12}")
    for name, label, p50, p99, size in rows:
        print(f"{name:<12}{label:<34}{p50:>10.2f}{p99:>10.2f}{size / 1024:>12.1f}")


if __name__ == "__main__":
    main()
