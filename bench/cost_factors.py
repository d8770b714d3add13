"""What a terrain or an objective costs against flat ground scored by speed, the figures behind
`softevo.api.cost.TERRAIN_COST` and `OBJECTIVE_COST`: `python bench/cost_factors.py [ROUNDS]
[PRESET] [alone]`.

Simulates the same 8 random robots of PRESET (default paper-voxel: 4x4x4, 10 s) on each
terrain, with and without the actuators' work measured (the `efficiency` objective), through
`simulate_batch` as the evaluators do (or one at a time with `alone`), in interleaved rounds,
and prints the least CPU seconds (process time: steadier than wall time on a shared machine)
of each case and its ratio to flat ground.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from softevo.core.config import resolve
from softevo.core.physics.evaluation import warm_up
from softevo.core.physics.simulate import simulate, simulate_batch

CASES = {  # name: terrain, measure energy
    "flat": ({"kind": "flat"}, False),
    "efficiency": ({"kind": "flat"}, True),
    "slope 10": ({"kind": "slope", "angle_deg": 10}, False),
    "slope -30": ({"kind": "slope", "angle_deg": -30}, False),
    "steps": ({"kind": "steps"}, False),
    "hurdles": ({"kind": "hurdles"}, False),
    "rough 0.2": ({"kind": "rough"}, False),
    "rough 100": ({"kind": "rough", "amplitude": 100, "wavelength": 3}, False),
    "rough 100 + efficiency": ({"kind": "rough", "amplitude": 100, "wavelength": 3}, True),
}


def main() -> None:
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    preset = sys.argv[2] if len(sys.argv) > 2 else "paper-voxel"
    alone = len(sys.argv) > 3 and sys.argv[3] == "alone"
    warm_up()
    encoding = resolve({"preset": preset}).make_encoding()
    rng = np.random.default_rng(1)
    genomes = [encoding.random(rng) for _ in range(8)]
    least = dict.fromkeys(CASES, float("inf"))
    for _ in range(rounds):
        for name, (terrain, energy) in CASES.items():
            sim = resolve({"preset": preset, "sim": {"terrain": terrain}}).sim
            robots = [encoding.to_robot(genome, sim) for genome in genomes]
            started = time.process_time()
            if alone:
                for robot in robots:
                    simulate(robot, energy=energy)
            else:
                simulate_batch(robots, energy=energy, small_alone=True)
            least[name] = min(least[name], time.process_time() - started)
    for name, seconds in least.items():
        print(f"{name:24s} {seconds:7.3f} s  {seconds / least['flat']:.2f} x flat")


if __name__ == "__main__":
    main()
