"""How long a local pool takes to start: `python bench/pool_start.py [--repeats N] [--pools K]`.

A `PoolEvaluator` of 2 processes is made and each process simulates one tiny robot (so both
have started and loaded the kernels); the wall time from making the pool to both results is a
pool's start. Each measurement is a fresh interpreter that starts K pools one after the other:
the first pays for the fork server (importing the physics and loading the kernels once), the
others find it running, as a service does when a cancel replaces its pool. Pool processes
started the old way (spawned: each imports numba and loads the kernels itself) and the new way
(forked from the fork server) are interleaved, A B A B, and the medians compared.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import platform
import statistics
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor

METHODS = ("spawn", "forkserver")


def once(method: str, pools: int) -> list[float]:
    """Seconds to start each of `pools` pools, one after the other, in this process."""
    from softevo.core.config import resolve
    from softevo.core.physics import evaluation
    from softevo.core.robots.robot_file import robot_to_json
    from softevo.core.search.evolution import Evolution

    if method == "spawn":  # the way before the fork server
        evaluation.pool_context = lambda: multiprocessing.get_context("spawn")  # type: ignore[assignment]
    run = Evolution.start(
        resolve(
            {
                "preset": "quick",
                "population": 2,
                "seed": 3,
                "sim": {"duration": 0.2, "settle_time": 0.1},
            }
        )
    )
    files = [robot_to_json(run.robot(item)) for item in run.individuals()]
    seconds = []
    for _ in range(pools):
        started = time.perf_counter()
        pool = evaluation.PoolEvaluator(2)
        with ThreadPoolExecutor(2) as threads:  # two batches at once: one in each process
            list(threads.map(pool.evaluate_batch, ([file] for file in files)))
        seconds.append(time.perf_counter() - started)
        pool.close()
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--pools", type=int, default=3, help="pools started per interpreter")
    parser.add_argument("--once", choices=METHODS, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.once:
        print(json.dumps(once(args.once, args.pools)))
        return
    print(
        f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python "
        f"{platform.python_version()}, pools of 2 processes, {args.pools} pools per "
        f"interpreter, median of {args.repeats} (interleaved)"
    )
    found: dict[str, list[list[float]]] = {method: [] for method in METHODS}
    for _ in range(args.repeats):
        for method in METHODS:
            command = [sys.executable, __file__, "--once", method, "--pools", str(args.pools)]
            out = subprocess.run(command, capture_output=True, text=True, check=True)
            found[method].append(json.loads(out.stdout.strip().splitlines()[-1]))
    medians = {}
    print("start method   first pool   later pools")
    for method in METHODS:
        first = statistics.median(times[0] for times in found[method])
        later = statistics.median(t for times in found[method] for t in times[1:])
        medians[method] = (first, later)
        print(f"{method:12} {first:10.3f} s {later:11.3f} s")
    (spawn_first, spawn_later), (fork_first, fork_later) = medians["spawn"], medians["forkserver"]
    print(
        f"forkserver: first pool {spawn_first / fork_first:.2f}x, later pools "
        f"{spawn_later / fork_later:.2f}x quicker to start than spawned"
    )


if __name__ == "__main__":
    main()
