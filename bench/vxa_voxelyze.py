"""Exported robots in evosoro's Voxelyze against softevo: `SOFTEVO_VOXELYZE=/path/to/voxelyze
python bench/vxa_voxelyze.py [--boxes 1|2pi|both] [--profile paper|physical]`.

The binary is evosoro's command-line Voxelyze (skriegman/evosoro, `evosoro/_voxcad/Voxelyze`
then `evosoro/_voxcad/voxelyzeMain`); softevo neither ships nor builds it (docs/export.md says
how). For the example robots and the nine boxes' champions (`docs/experiments/best_<box>.json`,
1 rad/s, and `best_fast_<box>.json`, 2 pi rad/s), this exports each robot with `softevo.core.
export`, runs the file as it is in a fresh folder (`voxelyze -f robot.vxa -p`), and prints a
markdown table, per robot:

* whether Voxelyze wrote the fitness file the GA section names;
* the net horizontal displacement of the centre of mass over softevo's fitness clock (settle_time
  to duration) in both: softevo's `SimResult.distance`, and Voxelyze's from the fitness file's
  CMTrace (linear between trace points at settle_time); the heading of each (degrees from +x);
* an actuated voxel's size swing (half peak to peak, in edge lengths) and period, in both, from
  a least-squares sine fit over the clock: softevo's voxel measured as the mean of its 12 edges,
  Voxelyze's as the size that engine prints for its voxel 0 (its voxels are rigid cubes whose
  size it sets). Voxelyze prints voxel 0 only, so when the robot's voxel 0 is passive the robot
  is turned about z or mirrored (a symmetry of both simulators' floor and gravity) until its
  voxel 0 is actuated, for this measurement only, and softevo measures the same voxel;

The examples include the crawler made a co-designed (`voxel-phase`) robot with random per-voxel
phases and amplitudes (seed 40), since no evolved one is stored. Then the Spearman rank
correlation of the champions' speeds between the two simulators.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from profiles import in_profile
from scipy.stats import spearmanr

from softevo.core.outputs.export import ExportError, export_robot
from softevo.core.physics import simulate
from softevo.core.robots.robot import Robot, VoxelRobot, build_mechanics
from softevo.core.robots.robot_file import load_robot
from softevo.core.robots.settings import PROFILES

ROOT = Path(__file__).resolve().parent.parent
BOXES = ("3x3x6", "4x4x3", "4x4x4", "5x5x3", "5x5x4", "5x5x5", "6x6x3", "6x6x6", "9x9x2")
EXAMPLES = ("breathing_cube", "crawler_4x4x4", "paper_cube")
ACTUATED = ("sine", "neg_sine")
#: softevo positions recorded every this many seconds for the size of a voxel.
RECORD_SECONDS = 0.01


@dataclass
class Swing:
    amplitude: float  # half peak to peak of the fitted sine, edge lengths
    period: float  # s
    phase: float  # degrees: the fit is m + amplitude sin(2 pi t / period + phase)


@dataclass
class Row:
    name: str
    voxels: int
    fitness_file: bool
    softevo: float  # displacement over the clock (m)
    voxelyze: float
    heading_softevo: float
    heading_voxelyze: float
    swing_softevo: Swing | None
    swing_voxelyze: Swing | None


def fit_sine(times: np.ndarray, values: np.ndarray, omega: float) -> Swing:
    """The sine m + p sin(w t) + q cos(w t) closest to `values` (least squares), w searched
    from 0.5 to 1.5 times `omega` in steps of 1/4000 of it: its amplitude hypot(p, q) and period
    2 pi / w (to about 0.03 %)."""
    best = (math.inf, 0.0, omega, 0.0)
    for trial in np.linspace(0.5 * omega, 1.5 * omega, 4001):
        basis = np.column_stack([np.ones_like(times), np.sin(trial * times), np.cos(trial * times)])
        coef, residual, *_ = np.linalg.lstsq(basis, values, rcond=None)
        error = float(residual[0]) if len(residual) else math.inf
        if error < best[0]:
            phase = math.degrees(math.atan2(coef[2], coef[1]))
            best = (error, float(math.hypot(coef[1], coef[2])), float(trial), phase)
    return Swing(best[1], 2 * math.pi / best[2], best[3])


def turned(robot: VoxelRobot, flip_x: bool, flip_y: bool, swap: bool) -> VoxelRobot:
    """The same robot turned about z / mirrored (labels, phases and amplitudes alike)."""

    def move(values: tuple) -> tuple:
        nx, ny, nz = robot.shape
        grid = np.array(values, dtype=object).reshape(nz, ny, nx)
        grid = grid[:, :, ::-1] if flip_x else grid
        grid = grid[:, ::-1, :] if flip_y else grid
        grid = grid.transpose(0, 2, 1) if swap else grid
        return tuple(grid.ravel().tolist())

    nx, ny, nz = robot.shape
    return VoxelRobot(
        shape=(ny, nx, nz) if swap else (nx, ny, nz),
        voxels=move(robot.voxels),
        actuation=robot.actuation,
        sim=robot.sim,
        phases=None if robot.phases is None else move(robot.phases),
        amplitudes=None if robot.amplitudes is None else move(robot.amplitudes),
    )


def first_voxel_actuated(robot: VoxelRobot) -> VoxelRobot | None:
    """A turn of `robot` whose first simulated voxel (x fastest, then y, then z: Voxelyze's
    voxel 0) is actuated, or None."""
    for flip_x in (False, True):
        for flip_y in (False, True):
            for swap in (False, True):
                candidate = turned(robot, flip_x, flip_y, swap)
                kept = build_mechanics(candidate).lattice.kept
                first = int(np.argmax(kept))
                if candidate.voxels[first] in ACTUATED:
                    return candidate
    return None


def voxel_size(robot: VoxelRobot, frames: np.ndarray, voxel: int) -> np.ndarray:
    """Mean length of voxel `voxel`'s 12 edges in every frame [F, M, 3], in edge lengths."""
    lattice = build_mechanics(robot).lattice
    nx, ny, _ = robot.shape
    x, y, z = voxel % nx, (voxel // nx) % ny, voxel // (nx * ny)
    corners = [(x + (i & 1), y + ((i >> 1) & 1), z + ((i >> 2) & 1)) for i in range(8)]
    keys = [cx + (nx + 1) * (cy + (ny + 1) * cz) for cx, cy, cz in corners]
    mass = np.searchsorted(lattice.points, keys)
    edges = [(i, i | bit) for i in range(8) for bit in (1, 2, 4) if not i & bit]
    lengths = [np.linalg.norm(frames[:, mass[a]] - frames[:, mass[b]], axis=1) for a, b in edges]
    return np.mean(lengths, axis=0) / robot.sim.edge_length


def heading(shift: np.ndarray) -> float:
    return math.degrees(math.atan2(shift[1], shift[0]))


def softevo_run(robot: VoxelRobot, voxel: int | None) -> tuple[float, float, Swing | None]:
    """softevo's displacement over its clock, heading, and voxel `voxel`'s swing."""
    every = max(1, round(RECORD_SECONDS / robot.sim.step))
    result, trajectory = simulate(robot, record_every=every, energy=False)
    shift = np.subtract(result.com_end, result.com_start)
    swing = None
    if voxel is not None and robot.sim.omega > 0:
        size = voxel_size(robot, trajectory.frames, voxel)
        clock = trajectory.times >= robot.sim.settle_time
        swing = fit_sine(trajectory.times[clock], size[clock], robot.sim.omega)
    return result.distance, heading(shift), swing


@dataclass
class VoxelyzeOut:
    wrote: bool
    distance: float
    heading: float
    swing: Swing | None


def voxelyze_run(binary: str, robot: VoxelRobot, measure_voxel: bool) -> VoxelyzeOut:
    """Run `robot`'s vxa in a fresh folder, as it is; read stdout and the fitness file."""
    with tempfile.TemporaryDirectory() as folder:
        (Path(folder) / "robot.vxa").write_bytes(export_robot(robot, "vxa"))
        done = subprocess.run(
            [binary, "-f", "robot.vxa", "-p"],
            cwd=folder,
            capture_output=True,
            text=True,
            timeout=600,
            check=False,
        )
        fitness = Path(folder) / "softevo_fitness.xml"
        if not fitness.exists():
            return VoxelyzeOut(False, math.nan, math.nan, None)
        trace = ET.parse(fitness).getroot().findall("./CMTrace/TraceStep")
    times = np.array([float(step.findtext("Time")) for step in trace])
    cm = np.array([[float(step.findtext(f"Trace{axis}")) for axis in "XY"] for step in trace])
    settle = robot.sim.settle_time
    start = np.array([np.interp(settle, times, cm[:, axis]) for axis in (0, 1)])
    shift = cm[-1] - start
    swing = None
    if measure_voxel and robot.sim.omega > 0:
        printed = re.findall(r"Time: (\S+)\nCM: \S+\n\nVox\[0\]  Scale: (\S+)", done.stdout)
        samples = np.array(printed, dtype=np.float64)
        clock = samples[:, 0] >= settle
        size = samples[clock, 1] / robot.sim.edge_length
        swing = fit_sine(samples[clock, 0], size, robot.sim.omega)
    return VoxelyzeOut(True, float(np.hypot(*shift)), heading(shift), swing)


def compare(binary: str, name: str, robot: Robot) -> Row | str:
    """One robot in both simulators, or the line saying why it cannot be exported."""
    try:
        export_robot(robot, "vxa")
    except ExportError as error:
        return f"{name}: not exported ({error})"
    voxels = int(build_mechanics(robot).lattice.kept.sum())
    whole = voxelyze_run(binary, robot, measure_voxel=False)
    distance, softevo_heading, _ = softevo_run(robot, None)
    probe = first_voxel_actuated(robot)
    swings: tuple[Swing | None, Swing | None] = (None, None)
    if probe is not None:
        voxel = int(np.argmax(build_mechanics(probe).lattice.kept))
        swings = (softevo_run(probe, voxel)[2], voxelyze_run(binary, probe, True).swing)
    return Row(
        name, voxels, whole.wrote, distance, whole.distance, softevo_heading, whole.heading, *swings
    )


def _swing_text(swing: Swing | None) -> str:
    if swing is None:
        return "-"
    return f"{swing.amplitude:.4f} / {swing.period:.4f} s / {round(swing.phase) + 0:d}"


def table(rows: list[Row]) -> str:
    lines = [
        "| robot | voxels | fitness file | displacement softevo (m) | displacement Voxelyze (m) "
        "| heading softevo / Voxelyze (deg) | voxel swing / period / phase (deg) softevo "
        "| voxel swing / period / phase (deg) Voxelyze |",
        "| --- | ---: | :---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for row in rows:
        lines.append(
            f"| {row.name} | {row.voxels} | {'yes' if row.fitness_file else 'NO'} "
            f"| {row.softevo:.4f} | {row.voxelyze:.4f} "
            f"| {row.heading_softevo:.0f} / {row.heading_voxelyze:.0f} "
            f"| {_swing_text(row.swing_softevo)} | {_swing_text(row.swing_voxelyze)} |"
        )
    return "\n".join(lines)


def co_designed(crawler: VoxelRobot) -> VoxelRobot:
    """The crawler as a `voxel-phase` robot: every voxel its own phase in [-pi, pi] and amplitude
    gene in [-pi/2, pi/2] (the encoding's ranges), drawn with seed 40. No such robot is stored."""
    rng = np.random.default_rng(40)
    n = len(crawler.voxels)
    return VoxelRobot(
        crawler.shape,
        crawler.voxels,
        crawler.actuation,
        crawler.sim,
        phases=tuple(rng.uniform(-math.pi, math.pi, n).tolist()),
        amplitudes=tuple(rng.uniform(-math.pi / 2, math.pi / 2, n).tolist()),
    )


def robots(boxes: str, profile: str | None) -> list[tuple[str, Robot]]:
    """The examples and champions, in `profile` where one is given (else as their files say)."""
    chosen = [(name, load_robot(ROOT / "examples" / f"{name}.json")) for name in EXAMPLES]
    chosen.append(("crawler_4x4x4 voxel-phase (seed 40)", co_designed(chosen[1][1])))
    folder = ROOT / "docs" / "experiments"
    if boxes in ("1", "both"):
        chosen += [(f"best {b} (1 rad/s)", load_robot(folder / f"best_{b}.json")) for b in BOXES]
    if boxes in ("2pi", "both"):
        chosen += [(f"best {b} (2 pi)", load_robot(folder / f"best_fast_{b}.json")) for b in BOXES]
    if profile is None:
        return chosen
    return [(name, in_profile(robot, profile)) for name, robot in chosen]


def rank_correlations(rows: list[Row]) -> list[str]:
    lines = []
    for tag in ("(1 rad/s)", "(2 pi)"):
        mine = [row for row in rows if row.name.endswith(tag)]
        if len(mine) > 2:
            rho = spearmanr([r.softevo for r in mine], [r.voxelyze for r in mine]).statistic
            lines.append(f"Spearman rank correlation of the {len(mine)} champions {tag}: {rho:.3f}")
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--boxes", choices=("1", "2pi", "both"), default="both")
    parser.add_argument("--profile", choices=tuple(PROFILES), help="re-set every robot in it")
    args = parser.parse_args(argv)
    binary = os.environ.get("SOFTEVO_VOXELYZE", "")
    if not binary or not os.access(binary, os.X_OK):
        print("vxa_voxelyze: set SOFTEVO_VOXELYZE to evosoro's voxelyze binary", file=sys.stderr)
        return 2
    rows, notes = [], []
    for name, robot in robots(args.boxes, args.profile):
        outcome = compare(binary, name, robot)
        (notes if isinstance(outcome, str) else rows).append(outcome)
        print(outcome if isinstance(outcome, str) else f"{name}: done", file=sys.stderr)
    print(table(rows))
    print()
    print("\n".join(notes + rank_correlations(rows)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
