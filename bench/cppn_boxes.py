"""Kernel cost of CPPN bodies in big boxes: `python bench/cppn_boxes.py [ROBOTS] [SECONDS]`.

For each box (4x4x4, 6x6x6, 8x8x8, 10x10x10) it grows ROBOTS (4) random `cppn` genomes (seed 1)
and times, per robot, the decode (network -> labels) and one `simulate` of SECONDS (2) simulated
seconds at the paper's dt, on one thread (numba warmed first). Prints the masses and springs
actually built, seconds per simulated second, and spring-steps per second, with each box's
ratio to 4x4x4. Results on the 2-core machine: BENCHMARKS.md.
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np

from softevo.core.physics.simulate import simulate
from softevo.core.robots.cppn import CppnEncoding
from softevo.core.robots.robot import build_mechanics
from softevo.core.robots.settings import SimSettings

BOXES = ((4, 4, 4), (6, 6, 6), (8, 8, 8), (10, 10, 10))


def measure(shape: tuple[int, int, int], robots: int, seconds: float) -> dict[str, float]:
    """Medians over `robots` random CPPN bodies of `shape`."""
    encoding, rng = CppnEncoding(shape), np.random.default_rng(1)
    sim = SimSettings(duration=seconds, settle_time=0.0)
    decode, wall, springs, masses, rates = [], [], [], [], []
    while len(wall) < robots:
        genome = encoding.random(rng)
        started = time.perf_counter()
        robot = encoding.to_robot(genome, sim)
        decode.append(time.perf_counter() - started)
        if all(label == "empty" for label in robot.voxels):
            continue  # no body: nothing to simulate
        mech = build_mechanics(robot)
        result, _ = simulate(mech, energy=False)
        wall.append(result.wall_seconds)
        springs.append(mech.n_springs)
        masses.append(mech.n_masses)
        rates.append(mech.n_springs * sim.n_steps / wall[-1])
    return {
        "decode_ms": 1000 * statistics.median(decode),
        "masses": statistics.median(masses),
        "springs": statistics.median(springs),
        "s_per_sim_s": statistics.median(wall) / seconds,
        "spring_steps_per_s": statistics.median(rates),
    }


def main() -> None:
    robots = int(sys.argv[1]) if len(sys.argv) > 1 else 4
    seconds = float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
    measure((2, 2, 2), 1, 0.1)  # compile
    base = None
    print("box        decode ms  masses  springs  wall s / sim s  ratio  spring-steps/s")
    for shape in BOXES:
        row = measure(shape, robots, seconds)
        base = base or row
        ratio = row["s_per_sim_s"] / base["s_per_sim_s"]
        print(
            f"{'x'.join(map(str, shape)):10} {row['decode_ms']:9.2f} {row['masses']:7.0f} "
            f"{row['springs']:8.0f} {row['s_per_sim_s']:15.3f} {ratio:6.2f} "
            f"{row['spring_steps_per_s']:15.3g}"
        )


if __name__ == "__main__":
    main()
