"""Evolution benchmark: `python bench/evolution.py [--quick]`.

Prints, for the `paper-voxel` preset (4x4x4, population 25, 10 s simulations of 20,000 steps):
evaluations per second through the serial evaluator and a local pool of 1 and 2 processes (one
generation of 50 random robots through the generation step, the same robots for each, results
checked identical), then one whole run with the default pool:
its wall time (target: under 60 s on a 2-core machine), simulations run and the share of
individuals whose fitness came from the hash cache.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from softevo.core.config import RunConfig, resolve
from softevo.core.evaluator import Evaluator
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import PoolEvaluator, SerialEvaluator


def evaluations_per_second(
    config: RunConfig, evaluator: Evaluator, repeats: int
) -> tuple[float, np.ndarray]:
    """One generation of `config` (a random search) through the step, `repeats` times, each
    with a fresh cache; the first, untimed, warms every process's kernels."""
    times, fitness = [], np.empty(0)
    for repeat in range(repeats + 1):
        evolution = Evolution.start(config)
        started = time.perf_counter()
        evolution.step(evaluator)
        if repeat:
            times.append(time.perf_counter() - started)
        fitness = np.asarray(evolution.state.previous_fitness, dtype=np.float64)
    return len(fitness) / float(np.median(times)), fitness


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer robots and generations")
    args = parser.parse_args()
    config = resolve({"preset": "paper-voxel", "seed": 1})
    if args.quick:
        config = resolve({"preset": "paper-voxel", "seed": 1, "generations": 10})
    n_robots = 12 if args.quick else 50
    robots = resolve(
        {"preset": "paper-voxel", "seed": 1, "algorithm": "random", "population": n_robots}
    )
    repeats = 1 if args.quick else 3

    print(
        f"machine: {os.cpu_count()} cores, {platform.processor() or platform.machine()}, "
        f"Python {platform.python_version()}"
    )
    print(f"paper-voxel robots: {n_robots} random 4x4x4, {config.sim.n_steps} steps each\n")
    print(f"{'evaluator':<24}{'evaluations/s':>15}{'vs serial':>11}")
    serial_rate, reference = evaluations_per_second(robots, SerialEvaluator(), repeats)
    print(f"{'serial (this process)':<24}{serial_rate:>15.2f}{1.0:>11.2f}")
    for processes in (1, 2):
        with PoolEvaluator(processes) as pool:
            rate, result = evaluations_per_second(robots, pool, repeats)
        same = np.array_equal(result, reference, equal_nan=True)
        label = f"pool, {processes} process{'es' if processes > 1 else ''}"
        print(f"{label:<24}{rate:>15.2f}{rate / serial_rate:>11.2f}   identical to serial: {same}")

    print(f"\nwhole run: paper-voxel 4x4x4, seed 1, {config.generations} generations, pool of 2")
    started = time.perf_counter()
    evolution = Evolution.start(config)
    with PoolEvaluator(2) as pool:
        evolution.run(pool)
    wall = time.perf_counter() - started
    individuals = evolution.evaluations + evolution.saved
    best = evolution.best_robot()
    print(f"  wall time            {wall:8.1f} s (target < 60 s for 100 generations)")
    print(f"  simulations run      {evolution.evaluations:8d} of {individuals} individuals")
    print(f"  saved by the cache   {evolution.saved / individuals:8.1%}")
    print(f"  best speed           {best[1]:8.4f} m/s (generation {best[2]})")


if __name__ == "__main__":
    main()
