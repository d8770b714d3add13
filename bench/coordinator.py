"""The coordinator's own cost: `python bench/coordinator.py [--generations G] [--tree PATH]`.

Drives `paper-voxel` runs (4x4x4, population 25) through the service's `Coordinator` on SQLite
and on PostgreSQL with an instant evaluator (a robot's fitness is a cheap function of its file,
no simulation), so every CPU second this process spends is the coordinator's: breeding, robot
files, the store's writes and the generation commits. Prints CPU per individual (ms), wall time
and generations of 25 committed per second.

`--tree PATH` measures another checkout instead (an older commit in a `git worktree`, whose
packages were still installed as top-level `core` and `api`): the same runs, the same evaluator,
the version's own coordinator and store.
"""

from __future__ import annotations

import argparse
import importlib
import os
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

POSTGRES = os.environ.get("SOFTEVO_TEST_POSTGRES", "postgresql://postgres@127.0.0.1:5432/test")


def modules(tree: str | None) -> dict[str, Any]:
    """The coordinator, database and run creation of this checkout, or of the one at `tree`."""
    if tree is None:
        prefix, store = "softevo.", "softevo.api.store"
    else:
        sys.path.insert(0, tree)
        prefix, store = "", "api.storage"
    load = importlib.import_module
    return {
        "Coordinator": load(f"{prefix}api.coordinator").Coordinator,
        "db": load(f"{prefix}api.db"),
        "create_run": load(store).create_run,
        "get_run": load(store).get_run,
        "resolve": load(f"{prefix}core.config").resolve,
        "BatchResult": load(f"{prefix}core.evaluator").BatchResult,
    }


def instant_evaluator(found: dict[str, Any]) -> Any:
    """Both generations of the evaluator interface (`evaluate_batch` + `capacity` now;
    `evaluate_batch`, `evaluate`, `workers` and `concurrency` before), no simulation."""
    batch_result = found["BatchResult"]

    class Instant:
        concurrency = 2

        def evaluate(self, files: list[dict]) -> np.ndarray:
            return np.array([
                sum(v in ("sine", "neg_sine") for v in f["voxels"]) / len(f["voxels"])
                for f in files
            ])  # fmt: skip

        def evaluate_batch(self, files: list[dict], key: str | None = None) -> Any:
            return batch_result(self.evaluate(files), "instant", 0.0)

        def capacity(self) -> int:
            return 2

        workers = capacity

        def close(self) -> None:
            pass

        def __enter__(self) -> Instant:
            return self

        def __exit__(self, *exc: object) -> None:
            pass

    if hasattr(sys.modules.get(batch_result.__module__), "Evaluator"):
        base = sys.modules[batch_result.__module__].Evaluator
        if getattr(base, "__abstractmethods__", None):  # the ABC of this version
            return type("InstantEvaluator", (Instant, base), {})()
    return Instant()


def drive(found: dict[str, Any], url: str, generations: int) -> tuple[float, float, int]:
    """One run to completion: (CPU seconds of this process, wall seconds, individuals)."""
    database = found["db"].Database(url)
    database.upgrade()
    config = found["resolve"]({"preset": "paper-voxel", "seed": 1, "generations": generations})
    run = found["create_run"](database, config)
    coordinator = found["Coordinator"](database, instant_evaluator(found), batch_size=4)
    cpu, wall = time.process_time(), time.perf_counter()
    coordinator.start()
    while found["get_run"](database, run.id).status in ("queued", "running"):
        time.sleep(0.2)  # rarely: this process's CPU is what is measured
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    coordinator.stop()
    status = found["get_run"](database, run.id).status
    database.dispose()
    if status != "completed":
        raise SystemExit(f"run ended {status}")
    return cpu, wall, config.population * generations


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--generations", type=int, default=60)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--tree", help="measure the checkout at this path instead")
    args = parser.parse_args()
    found = modules(args.tree)
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, tree {args.tree or 'this checkout'}")  # fmt: skip
    print("database    CPU/individual  wall/generation  generations/s (median of repeats)")
    for name in ("sqlite", "postgres"):
        rows = []
        for _ in range(args.repeats):
            if name == "sqlite":
                with tempfile.TemporaryDirectory() as folder:
                    rows.append(
                        drive(found, f"sqlite:///{Path(folder) / 'b.db'}", args.generations)
                    )
            else:
                with found["db"].scratch_postgres(POSTGRES, "softevo_bench") as url:
                    rows.append(drive(found, url, args.generations))
        cpu = statistics.median(c / n for c, _, n in rows) * 1e3
        per_generation = statistics.median(w / args.generations for _, w, _ in rows)
        print(f"{name:10}  {cpu:11.3f} ms  {per_generation * 1e3:12.2f} ms  "
              f"{1 / per_generation:12.1f}")  # fmt: skip


if __name__ == "__main__":
    main()
