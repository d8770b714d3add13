"""Regenerate the example robot files: `python examples/make_examples.py` (about 20 s).

* breathing_cube.json: the paper's phase 1, one actuated cube dropped from 1 m that breathes.
* paper_cube.json: the paper's phase 2, one cube whose 28 springs each pick one of the four
  [k, b, w, c] options (drawn with seed 2).
* crawler_4x4x4.json: the fastest of 96 random 4x4x4 voxel robots (seed 1) under the paper's
  settings: a robot that crawls.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from softevo.core.physics import simulate_batch
from softevo.core.robots.encodings import PAPER_CUBE_OPTIONS
from softevo.core.robots.robot import LABELS, Actuation, SpringRobot, VoxelRobot
from softevo.core.robots.robot_file import dump_robot
from softevo.core.robots.settings import sim_settings

HERE = Path(__file__).parent


def main() -> None:
    breathing = VoxelRobot(
        shape=(1, 1, 1),
        voxels=("sine",),
        actuation=Actuation(a=0.0, b=1.0, c=0.0),
        sim=sim_settings({"drop_height": 1.0, "omega": 2 * math.pi, "duration": 5.0}),
    )
    dump_robot(breathing, HERE / "breathing_cube.json")
    # the copy `softevo reproduce` ships inside the package (an installed softevo has no examples/)
    dump_robot(breathing, HERE.parent / "softevo" / "reproduce" / "data" / "breathing_cube.json")

    rng = np.random.default_rng(2)
    cube = SpringRobot(
        shape=(1, 1, 1),
        filled=(True,),
        springs=np.array(PAPER_CUBE_OPTIONS)[rng.integers(0, 4, size=28)],
        sim=sim_settings(),
    )
    dump_robot(cube, HERE / "paper_cube.json")

    rng = np.random.default_rng(1)
    labels = np.array(LABELS)
    candidates = [
        VoxelRobot(
            shape=(4, 4, 4),
            voxels=tuple(str(label) for label in rng.choice(labels, 64)),
            actuation=Actuation(
                float(rng.uniform(-1, 1)),
                float(rng.uniform(-math.pi / 2, math.pi / 2)),
                float(rng.uniform(-2 * math.pi, 2 * math.pi)),
            ),
        )
        for _ in range(96)
    ]
    speeds = np.array([result.speed for result in simulate_batch(candidates, threads=2)])
    best = int(np.nanargmax(speeds))
    print(f"crawler: candidate {best}, speed {speeds[best]:.4f} m/s")
    dump_robot(candidates[best], HERE / "crawler_4x4x4.json")


if __name__ == "__main__":
    main()
