"""Do results depend on the time step? `python bench/convergence.py [--profile paper|physical]
[--quick]`.

A fixed set of robots (the examples, the nine boxes' champions at 1 rad/s and at 2 pi rad/s, and
the crawler and the 4x4x4 champion on every task's terrain) simulated in one physics profile at
its step dt, at dt/2 and at dt/4. Prints, per robot, the speed at each step and the change of
speed, forward speed, climb rate and cost of transport from dt/4, then how many robots are
within the target (2 % of their dt/4 value, or 1 mm/s for a robot that hardly moves) and
whether the set ranks the same at dt as at dt/4 (Spearman's rho and the exact order).
`--quick`: the examples and three champions only (the test's small version of this).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

from profiles import in_profile
from scipy.stats import spearmanr

from softevo.core.physics import simulate_batch
from softevo.core.robots.robot import Robot
from softevo.core.robots.robot_file import load_robot
from softevo.core.robots.settings import PROFILES, sim_settings
from softevo.core.robots.tasks import TASKS

ROOT = Path(__file__).resolve().parent.parent
BOXES = ("3x3x6", "4x4x3", "4x4x4", "5x5x3", "5x5x4", "5x5x5", "6x6x3", "6x6x6", "9x9x2")
EXAMPLES = ("crawler_4x4x4", "breathing_cube", "paper_cube")
MEASURES = ("speed", "forward_speed", "climb_rate", "cost_of_transport")
#: Within target: |x - x_ref| <= RELATIVE |x_ref|, or <= FLOOR (m/s) for a speed near zero.
RELATIVE, FLOOR = 0.02, 1e-3


def robot_set(quick: bool) -> list[tuple[str, Robot]]:
    chosen = [(name, load_robot(ROOT / "examples" / f"{name}.json")) for name in EXAMPLES]
    folder = ROOT / "docs" / "experiments"
    boxes = BOXES[1:3] + BOXES[-1:] if quick else BOXES
    chosen += [(f"best {b} (1 rad/s)", load_robot(folder / f"best_{b}.json")) for b in boxes]
    if quick:
        return chosen
    chosen += [(f"best {b} (2 pi)", load_robot(folder / f"best_fast_{b}.json")) for b in BOXES]
    for task, (_, terrain, _) in TASKS.items():
        if terrain["kind"] == "flat":
            continue
        for name, robot in (chosen[0], chosen[5]):
            sim = sim_settings({**robot.sim.model_dump(), "terrain": terrain})
            chosen.append((f"{name} on {task}", dataclasses.replace(robot, sim=sim)))
    return chosen


def measures(robots: list[Robot]) -> list[dict[str, float]]:
    results = simulate_batch(robots, energy=True)
    return [{m: float(getattr(r, m)) for m in MEASURES} for r in results]


def within(value: float, reference: float) -> bool:
    return abs(value - reference) <= max(RELATIVE * abs(reference), FLOOR)


def run(profile: str, quick: bool) -> int:
    named = [(name, in_profile(robot, profile)) for name, robot in robot_set(quick)]
    steps = [robot.sim.step for _, robot in named]
    at = {
        k: measures(
            [in_profile(r, profile, dt=s / k) for (_, r), s in zip(named, steps, strict=True)]
        )
        for k in (1, 2, 4)
    }
    print(f"profile {profile}: dt = {min(steps):.4g} s (the smallest of the set)\n")
    print("| robot | speed dt | dt/2 | dt/4 (m/s) | speed | forward | climb | CoT |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    good = 0
    for i, (name, _) in enumerate(named):
        one, half, ref = at[1][i], at[2][i], at[4][i]
        changes = [_change(one[m], ref[m]) for m in MEASURES]
        good += within(one["speed"], ref["speed"])
        print(
            f"| {name} | {one['speed']:.4f} | {half['speed']:.4f} | {ref['speed']:.4f} | "
            + " | ".join(changes)
            + " |"
        )
    coarse = [row["speed"] for row in at[1]]
    fine = [row["speed"] for row in at[4]]
    rho = spearmanr(coarse, fine).statistic
    same = sorted(range(len(fine)), key=coarse.__getitem__) == sorted(
        range(len(fine)), key=fine.__getitem__
    )
    print(f"\nspeed within {RELATIVE:.0%} of dt/4 (or {FLOOR * 1000:g} mm/s): {good}/{len(named)}")
    print(f"ranking at dt against dt/4: Spearman {rho:.3f}, same order: {same}")
    return 0


def _change(value: float, reference: float) -> str:
    if not (math.isfinite(value) and math.isfinite(reference)):
        return "n/a"
    if abs(reference) < FLOOR:
        return f"{value - reference:+.1e}"
    return f"{(value - reference) / abs(reference):+.1%}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profile", choices=tuple(PROFILES), default="physical")
    parser.add_argument("--quick", action="store_true", help="a small set (the test's)")
    args = parser.parse_args(argv)
    return run(args.profile, args.quick)


if __name__ == "__main__":
    sys.exit(main())
