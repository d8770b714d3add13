"""The kernels' speed in each physics profile, against an earlier tree: `python
bench/kernel_profiles.py --tree OLD [--repeats N]`.

Spring updates per second per core (springs x steps x robots / wall seconds, one thread, the
median of `--repeats` runs, taken in turns A B A B so that the machine's drift falls on both) for
32 random actuated 4x4x4 robots of the paper's materials, batched (`simulate_batch`), and for one
of them alone (`simulate`): in this tree's paper and physical profiles, and in the tree at
`--tree` (a `git worktree` of an earlier commit, its own default settings) in a fresh
interpreter each. Prints the figures and the ratios to the earlier tree.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

from staged import stage

ROOT = Path(__file__).resolve().parent.parent
#: Run in each interpreter: the robots, a warm-up, then the timed calls; prints JSON rates.
PROBE = """
import json, sys, time
import numpy as np
from softevo.core.physics import simulate, simulate_batch
from softevo.core.robots.robot import Actuation, VoxelRobot, build_mechanics
from softevo.core.robots.settings import sim_settings
sim = sim_settings(json.loads(sys.argv[1]))
rng = np.random.default_rng(7)
labels = ("soft", "hard", "sine", "neg_sine")
robots = [VoxelRobot((4, 4, 4), tuple(rng.choice(labels, 64)), Actuation(0.1, 1.0, 0.3), sim)
          for _ in range(32)]
mechs = [build_mechanics(robot) for robot in robots]
simulate_batch(mechs[:2]); simulate(mechs[0])
started = time.perf_counter(); simulate_batch(mechs); batch = time.perf_counter() - started
started = time.perf_counter(); simulate(mechs[0]); alone = time.perf_counter() - started
springs = sum(m.n_springs for m in mechs) * sim.n_steps
dt = getattr(sim, "step", None) or sim.dt  # a tree before profiles has dt alone
print(json.dumps({"batched": springs / batch, "alone": mechs[0].n_springs * sim.n_steps / alone,
                  "dt": dt}))
"""
PAPER = {"duration": 2.0}
PHYSICAL = {"profile": "physical", "duration": 2.0}


def probe(path: Path | None, settings: dict) -> dict[str, float]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    if path is not None:
        env["PYTHONPATH"] = str(path)
    done = subprocess.run(
        [sys.executable, "-P", "-c", PROBE, json.dumps(settings)],
        capture_output=True,
        text=True,
        env=env,
        check=True,
        cwd="/",
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tree", type=Path, required=True, help="an earlier checkout")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    old = stage(args.tree.resolve())
    cases = {"earlier tree": (old, PAPER), "paper": (None, PAPER), "physical": (None, PHYSICAL)}
    found: dict[str, list[dict[str, float]]] = {name: [] for name in cases}
    for _ in range(args.repeats):
        for name, (path, settings) in cases.items():
            found[name].append(probe(path, settings))
    base = {kind: statistics.median(r[kind] for r in found["earlier tree"]) for kind in KINDS}
    print("| tree, profile | dt (s) | batched (M/s) | ratio | alone (M/s) | ratio |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for name, rows in found.items():
        rate = {kind: statistics.median(r[kind] for r in rows) for kind in KINDS}
        cells = [f"{rate[k] / 1e6:.0f} | {rate[k] / base[k]:.2f}" for k in KINDS]
        print(f"| {name} | {rows[0]['dt']:.4g} | " + " | ".join(cells) + " |")
    return 0


KINDS = ("batched", "alone")

if __name__ == "__main__":
    sys.exit(main())
