"""What one read costs on a large run: `python bench/read_routes.py [--individuals N]
[--population P] [--repeat R]`.

Builds a SQLite store with one completed run of N individuals (default 10,000: 100 generations
of 100) whose genomes are `voxel-phase` genomes of an 8x8x8 box (about 21 kB of JSON each, the
largest the service's defaults accept), inserted directly (no simulation), then, for each read
route, starts the app in a fresh process (TestClient, the coordinator idle) and asks it R times.
Printed per route: the median wall time of a request (ms) and the most memory one request added
to the process (MB: its peak resident set during the request, reset before each with
/proc/self/clear_refs, less its resident set before; Linux only).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
from sqlalchemy import insert, update

ROUTES = (
    "/runs/1/figures/population.png",
    "/runs/1/individuals?limit=5000",
    "/runs/1/individuals?generation=50",
    "/runs/1/curve?format=csv",
    "/runs/1",
)


def build(path: Path, individuals: int, population: int) -> None:
    """The store: one completed run, its curve and its individuals, written in chunks."""
    from softevo.api import store
    from softevo.api.db import Database
    from softevo.api.models import GenerationRow, IndividualRow, RunRow
    from softevo.core.config import RunConfig

    generations = individuals // population
    config = RunConfig.model_validate(
        {
            "preset": "quick",
            "shape": [8, 8, 8],
            "seed": 1,
            "encoding": "voxel-phase",
            "population": population,
            "generations": generations,
        }
    )
    db = Database(f"sqlite:///{path}")
    db.upgrade()
    run = store.create_run(db, config)
    encoding, rng, now = config.make_encoding(), np.random.default_rng(1), datetime.now(UTC)
    genomes = [encoding.random(rng) for _ in range(min(population, 200))]  # reused: same size
    with db.write_session() as session:
        for generation in range(generations):
            fitness = rng.normal(0.1, 0.05, population)
            session.execute(
                insert(IndividualRow),
                [
                    {
                        "run_id": run.id,
                        "generation": generation,
                        "index": index,
                        "genome": json.loads(genomes[index % len(genomes)].canonical),
                        "genome_hash": f"{generation:08d}{index:08d}",
                        "operator": "mutation",
                        "parents": [index],
                        "status": "evaluated",
                        "fitness": float(fitness[index]),
                        "eval_seconds": 0.5,
                        "worker": "bench",
                        "evaluated_at": now,
                    }
                    for index in range(population)
                ],
            )
            session.execute(
                insert(GenerationRow),
                [
                    {
                        "run_id": run.id,
                        "generation": generation,
                        "best": float(fitness.max()),
                        "mean": float(fitness.mean()),
                        "median": float(np.median(fitness)),
                        "min": float(fitness.min()),
                        "std": float(fitness.std()),
                        "best_so_far": float(fitness.max()),
                        "diversity": 0.5,
                        "size": population,
                        "failed": 0,
                        "evaluations": population,
                        "saved": 0,
                        "seconds": 1.0,
                        "committed_at": now,
                    }
                ],
            )
        session.execute(
            update(RunRow)
            .where(RunRow.id == run.id)
            .values(
                status="completed",
                generations_done=generations,
                evaluations=individuals,
                best_fitness=None,
                finished_at=now,
            )
        )
    db.dispose()


def _kib(field: str) -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    raise RuntimeError(f"no {field} in /proc/self/status")


def measure(path: Path, route: str, repeat: int) -> dict[str, float]:
    """In this (fresh) process: the route asked `repeat` times; median ms, most MB added."""
    from fastapi.testclient import TestClient

    from softevo.api.app import create_app
    from softevo.api.settings import Settings
    from softevo.core.physics.evaluation import SerialEvaluator

    settings = Settings(database_url=f"sqlite:///{path}", poll_seconds=60.0)
    seconds, added = [], []
    with TestClient(create_app(settings, lambda _s: SerialEvaluator())) as client:
        client.get("/runs/1/curve")  # the first request's own costs (imports, connections)
        for _ in range(repeat):
            Path("/proc/self/clear_refs").write_text("5")  # the peak starts again from now
            before = _kib("VmRSS")
            started = time.perf_counter()
            response = client.get(route)
            seconds.append(time.perf_counter() - started)
            added.append((_kib("VmHWM") - before) / 1024)
            assert response.status_code == 200, (route, response.status_code, response.text)
    return {"ms": 1000 * statistics.median(seconds), "mb": max(added)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--individuals", type=int, default=10_000)
    parser.add_argument("--population", type=int, default=100)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--measure", nargs=2, metavar=("DB", "ROUTE"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.measure:
        print(json.dumps(measure(Path(args.measure[0]), args.measure[1], args.repeat)))
        return
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "softevo.db"
        started = time.perf_counter()
        build(path, args.individuals, args.population)
        size = path.stat().st_size / 2**20
        print(
            f"store: {args.individuals} individuals (voxel-phase 8x8x8), {size:.0f} MB, "
            f"built in {time.perf_counter() - started:.1f} s"
        )
        print(f"{'route':40} {'ms (median)':>12} {'MB added (max)':>15}")
        for route in ROUTES:
            out = subprocess.run(
                [
                    sys.executable,
                    __file__,
                    "--repeat",
                    str(args.repeat),
                    "--measure",
                    str(path),
                    route,
                ],
                capture_output=True,
                text=True,
                check=True,
            ).stdout
            figures = json.loads(out.strip().splitlines()[-1])
            print(f"{route:40} {figures['ms']:12.0f} {figures['mb']:15.1f}")


if __name__ == "__main__":
    main()
