"""What evosoro's Voxelyze (skriegman/evosoro, `_voxcad/Voxelyze`) needs, per voxel and per run,
to swing each actuated voxel as softevo does (docs/export.md, "Actuation in Voxelyze").

That engine sets a voxel's size every step to (docs/export.md quotes the source):

    size / nominal = 1 + DevTempFact + TempAmpDamp_v x TempAmplitude x CTE_material
                                        x sin(2 pi (t / TempPeriod + PhaseOffset_v))

from `CurTime >= InitCmTime` on, clamped to at most 1 + `GrowthAmplitude`. The per-voxel
`PhaseOffset` (periods) and `TempAmpDamp` (a factor) are `Structure` layers; `FinalTempAmpDamp`
and `GrowthTime` ramp the factor linearly from `TempAmpDamp` from t = InitCmTime on;
`FinalVoxelSize` / `InitialVoxelSize` (units of GrowthAmplitude) add a constant size offset,
which softevo's gene a is, and scale down the actuation of a shrunk voxel by 1 + (size - 1) /
GrowthAmplitude, which `TempAmpDamp` undoes here.

softevo's voxel v: size 1 + offset_v + A_v sin(w t + phi_v), from t = 0. So the export writes
InitCmTime = 0 (actuation from t = 0, in phase with softevo's clock), CTE = the robot's signed
amplitude per material, TempAmpDamp_v = A_v / CTE, PhaseOffset_v = phi_v / (2 pi), and ramps
amplitude and offset from 0 over softevo's settle time (no jolt; softevo measures nothing then).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from softevo.core.robots.robot import VoxelRobot

#: Sign of each actuated label's wave (neg_sine is sine's anti-phase twin).
SIGNS = {"sine": 1.0, "neg_sine": -1.0}
#: GrowthAmplitude is written this much above the largest size, so float rounding of the product
#: CTE x TempAmpDamp x sin never meets Voxelyze's clamp.
CLAMP_MARGIN = 1e-6


@dataclass(frozen=True)
class VoxelActuation:
    """Per-voxel actuation of a robot, as grids [x, y, z] (0 where a voxel is empty or passive),
    and the Voxelyze numbers that reproduce it."""

    amplitude: np.ndarray  # A_v: signed relative size amplitude
    phase: np.ndarray  # phi_v (rad): c, plus the voxel's own phase for voxel-phase robots
    offset: np.ndarray  # constant relative size offset (softevo's offset_scale x a)
    cte: float  # CTE of `sine` (that of `neg_sine` is -cte)
    growth_amplitude: float  # GrowthAmplitude: bounds every size from above
    damp: np.ndarray  # TempAmpDamp_v once ramped: A_v / (sign cte), offset's shrink undone
    ramp: float  # seconds over which amplitude and offset grow from 0 (softevo's settle time)

    @property
    def actuated(self) -> bool:
        return bool(np.any(self.amplitude != 0) or np.any(self.offset != 0))


def _grid(values: np.ndarray, shape: tuple[int, int, int]) -> np.ndarray:
    """Flat per-voxel values (x fastest) as a grid [x, y, z]."""
    nx, ny, nz = shape
    return np.asarray(values, dtype=np.float64).reshape(nz, ny, nx).transpose(2, 1, 0)


def voxel_actuation(robot: VoxelRobot, grid: np.ndarray) -> VoxelActuation:
    """The actuation of each voxel of `grid` (softevo.core.outputs.export.voxel_grid: the simulated
    voxels), as softevo.core.robots.robot builds it, and its Voxelyze encoding."""
    sim, genes = robot.sim, robot.actuation
    n_voxels = len(robot.voxels)
    sign = np.vectorize(lambda label: SIGNS.get(label, 0.0), otypes=[np.float64])(grid)
    offset = np.where(sign != 0, sim.offset_scale * genes.a, 0.0)  # with or without a wave
    if sim.omega == 0:
        sign = np.zeros_like(sign)
    active = sign != 0
    gene = _grid(
        robot.amplitudes if robot.amplitudes is not None else [genes.b] * n_voxels, robot.shape
    )
    own_phase = _grid(robot.phases if robot.phases is not None else [0.0] * n_voxels, robot.shape)
    amplitude = sim.amplitude_scale * sign * gene
    phase = np.where(active, genes.c + own_phase, 0.0)
    largest = float(np.max(np.abs(gene[active]), initial=0.0))
    reference = genes.b if robot.amplitudes is None else largest
    cte = sim.amplitude_scale * (reference if reference != 0 else 1.0)
    growth = _growth_amplitude(amplitude, offset)
    shrink = np.minimum(1.0 + offset / growth, 1.0) if growth > 0 else np.ones_like(offset)
    damp = np.where(active, amplitude / (np.where(active, sign, 1.0) * cte) / shrink, 0.0)
    return VoxelActuation(amplitude, phase, offset, cte, growth, damp, sim.settle_time)


def _growth_amplitude(amplitude: np.ndarray, offset: np.ndarray) -> float:
    """The smallest GrowthAmplitude that never clamps a voxel's swing (largest size - 1), and
    at least twice the deepest shrink, so that Voxelyze's factor 1 + offset / GrowthAmplitude
    that scales a shrunk voxel's actuation stays at 1/2 or more."""
    largest = float(np.max(offset + np.abs(amplitude), initial=0.0))
    deepest = float(np.max(-offset, initial=0.0))
    return max(largest, 2 * deepest) * (1 + CLAMP_MARGIN)


def phase_periods(actuation: VoxelActuation) -> np.ndarray:
    """PhaseOffset: phi_v in periods (Voxelyze takes sin(2 pi (t / TempPeriod + PhaseOffset)))."""
    return actuation.phase / (2 * math.pi)


def structure_layers(actuation: VoxelActuation, duration: float) -> dict[str, np.ndarray]:
    """The per-voxel layers to write after the Structure's Data, by element name (grids [x, y,
    z]). With a ramp: TempAmpDamp 0 growing to FinalTempAmpDamp over GrowthTime (a fraction of
    the duration, as that engine reads it), and the offset as FinalVoxelSize grown alike;
    without one (settle time 0), TempAmpDamp and InitialVoxelSize at once, as softevo starts."""
    if not actuation.actuated:
        return {}
    layers = {"PhaseOffset": phase_periods(actuation)}
    has_offset = bool(np.any(actuation.offset != 0))
    size = actuation.offset / actuation.growth_amplitude if has_offset else None
    if actuation.ramp > 0:
        layers["TempAmpDamp"] = np.zeros_like(actuation.damp)
        layers["FinalTempAmpDamp"] = actuation.damp
        if size is not None:
            layers["FinalVoxelSize"] = size
        layers["GrowthTime"] = np.full_like(actuation.damp, actuation.ramp / duration)
    else:
        layers["TempAmpDamp"] = actuation.damp
        if size is not None:
            layers["InitialVoxelSize"] = size
    return layers


def slow_damping(robot: VoxelRobot, moduli: np.ndarray, voxel_mass: float) -> float:
    """SlowDampingZ: Voxelyze pulls each voxel's velocity toward 0 with the force
    -SlowDampingZ 2 sqrt(M E L) v, a decay rate 2 SlowDampingZ sqrt(E L / M); softevo multiplies
    every velocity by `velocity_factor` each step (the legacy `damping` and `drag`), a rate
    -ln(factor) / dt. Matched for the mean sqrt(E) of the robot's voxels (one number for all;
    stiffer voxels are damped more there)."""
    sim = robot.sim
    rate = -math.log(sim.velocity_factor) / sim.step
    mean_root = float(np.mean(np.sqrt(moduli * sim.edge_length / voxel_mass)))
    return rate / (2 * mean_root) if mean_root > 0 else 0.0


def drop_layers(robot: VoxelRobot) -> int:
    """Empty layers written under the robot so that it starts `drop_height` up, as in softevo:
    Voxelyze places layer k at z = k edge lengths and has no other start height. The nearest whole
    number of layers, so exact only for multiples of the edge length (docs/export.md)."""
    return round(robot.sim.drop_height / robot.sim.edge_length)
