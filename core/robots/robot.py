"""Robots: voxel grids with material labels, or lattices whose springs carry their own parameters,
and the rule that turns either into per-spring stiffness and rest-length actuation.

Actuation follows the paper's L0(t) = a + b*sin(w*t + c), read relative to each spring's rest
length L (so it does not depend on `edge_length`):

* a voxel labelled `sine` gives its springs L*(1 + offset_scale*a + amplitude_scale*b*sin(w t + c)),
  `neg_sine` the same with -sin; a, b, c are the robot's actuation genes and w is `sim.omega`;
* a spring with its own option [k, b, w, c] (the paper's phase 2 cube) has L*(1 + b*sin(w t + c)).

A spring shared by several voxels is the parallel combination of each voxel's own spring:
stiffness k = sum(k_v), rest length sum(k_v * L_v(t)) / k. This is exact: it gives the same force
as keeping every voxel's 28 springs separately, so a shared face is stiffer, as a solid is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from softevo.core.robots.lattice import (
    Lattice,
    LatticeError,
    build_lattice,
    full_lattice,
    spring_point_keys,
)
from softevo.core.robots.settings import SimSettings
from softevo.core.robots.terrain import start_shift

LABELS = ("empty", "soft", "hard", "sine", "neg_sine")
ACTUATED_LABELS = ("sine", "neg_sine")
#: Display colours (sRGB, 0..255) of the materials, the same in every picture, replay and export
#: (the dashboard's replay colours); "filled" for robots whose springs carry the materials.
COLOURS = {
    "soft": (0x9B, 0xC5, 0x9D),
    "hard": (0x4A, 0x4F, 0x55),
    "sine": (0xD1, 0x49, 0x5B),
    "neg_sine": (0x2F, 0x6F, 0xB5),
    "filled": (0xB8, 0xC2, 0xCC),
}
#: Bounds of the paper's phase 3 actuation genes.
GENE_BOUNDS = {"a": (-1.0, 1.0), "b": (-math.pi / 2, math.pi / 2), "c": (-2 * math.pi, 2 * math.pi)}


class RobotError(ValueError):
    """A robot that cannot be built; the message names the offending field."""


@dataclass(frozen=True)
class Actuation:
    """Per-robot actuation genes of sine / neg_sine voxels (paper phase 3)."""

    a: float = 0.0
    b: float = 0.0
    c: float = 0.0


@dataclass(frozen=True, eq=False)
class VoxelRobot:
    """A grid of labelled voxels; labels are listed x fastest, then y, then z.

    Co-designed gaits (the `voxel-phase` encoding) give every voxel its own `phases` (rad,
    added to the robot's c) and `amplitudes` (in place of the robot's b); only actuated voxels
    use theirs. Without them every actuated voxel shares the robot's genes, as in the paper,
    whose sine / neg_sine are phases 0 and pi."""

    shape: tuple[int, int, int]
    voxels: tuple[str, ...]
    actuation: Actuation = Actuation()
    sim: SimSettings = field(default_factory=SimSettings)
    phases: tuple[float, ...] | None = None
    amplitudes: tuple[float, ...] | None = None


@dataclass(frozen=True, eq=False)
class SpringRobot:
    """A lattice whose springs each carry [k, b, w, c] (the paper's phase 2 cube is 1x1x1).

    `filled` marks the voxels of the morphology; `springs` is a float array [S, 4] in the
    canonical spring order of `softevo.core.robots.lattice`.
    """

    shape: tuple[int, int, int]
    filled: tuple[bool, ...]
    springs: np.ndarray
    sim: SimSettings = field(default_factory=SimSettings)


@dataclass(frozen=True, eq=False)
class LabelledSpringRobot:
    """A voxel morphology whose every spring has its own material label (softevo's `spring`
    encoding: modules are single springs, not whole cubes).

    `filled` marks the voxels of the morphology. `spring_labels` gives one label of
    `SPRING_LABELS` to every spring of the *full* grid lattice (all voxels filled), in canonical
    order, so a genome's genes keep their place whatever the morphology; springs outside the built
    lattice are not expressed. A label gives its spring the material of a voxel with that label,
    without merging: the spring is a module of its own.
    """

    shape: tuple[int, int, int]
    filled: tuple[bool, ...]
    spring_labels: tuple[str, ...]
    actuation: Actuation = Actuation()
    sim: SimSettings = field(default_factory=SimSettings)


SPRING_LABELS = ("soft", "hard", "sine", "neg_sine")

Robot = VoxelRobot | SpringRobot | LabelledSpringRobot


@dataclass(frozen=True, eq=False)
class Mechanics:
    """Everything the kernel needs for one robot, as flat float64 / int64 arrays.

    Rest length of spring s at time t: rest_length[s] + amp_sin[s]*sin(omega t)
    + amp_cos[s]*cos(omega t) (the phase is folded into the two amplitudes).
    """

    lattice: Lattice
    positions: np.ndarray  # [M, 3] initial positions (m)
    stiffness: np.ndarray  # [S] (N/m)
    rest_length: np.ndarray  # [S] (m)
    amp_sin: np.ndarray  # [S] (m)
    amp_cos: np.ndarray  # [S] (m)
    omega: float  # (rad/s)
    sim: SimSettings

    @property
    def n_masses(self) -> int:
        return self.lattice.n_masses

    @property
    def n_springs(self) -> int:
        return self.lattice.n_springs


def _initial_positions(lattice: Lattice, sim: SimSettings) -> np.ndarray:
    """The lattice at rest, its lowest point `drop_height` above the terrain beneath it; on
    steps or hurdles moved along x so that its front face stands `FIRST_FEATURE_GAP` before
    the first riser or bar (`softevo.core.robots.terrain.start_shift`)."""
    positions = lattice.rest_positions * sim.edge_length
    if sim.terrain.kind == "flat":  # the original arithmetic, to the last bit
        positions[:, 2] += sim.drop_height - positions[:, 2].min()
        return positions
    shift = start_shift(sim.terrain, float(positions[:, 0].max()))
    if shift != 0.0:  # 0 on the task presets for a 4x4x4 robot filling its front layer
        positions[:, 0] += shift
    clearance = positions[:, 2] - sim.terrain.surface(positions[:, 0], positions[:, 1])
    positions[:, 2] += sim.drop_height - clearance.min()
    return positions


def _label_materials(
    labels: tuple[str, ...], sim: SimSettings, genes: Actuation
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-label stiffness (N/m), relative rest offset and signed relative amplitude."""
    table = {
        "empty": (0.0, 0.0, 0.0),
        "soft": (sim.soft_stiffness, 0.0, 0.0),
        "hard": (sim.hard_stiffness, 0.0, 0.0),
        "sine": (sim.actuated_stiffness, sim.offset_scale * genes.a, sim.amplitude_scale * genes.b),
        "neg_sine": (
            sim.actuated_stiffness,
            sim.offset_scale * genes.a,
            -sim.amplitude_scale * genes.b,
        ),
    }
    rows = np.array([table[label] for label in labels], dtype=np.float64).reshape(-1, 3)
    stiffness, rest, amplitude = (np.ascontiguousarray(column) for column in rows.T)
    return stiffness, rest, amplitude  # contiguous: one compile


def _voxel_mechanics(robot: VoxelRobot) -> Mechanics:
    unknown = sorted({label for label in robot.voxels if label not in LABELS})
    if unknown:
        raise RobotError(f"voxels: unknown label {unknown[0]!r} (labels: {', '.join(LABELS)})")
    filled = np.array([label != "empty" for label in robot.voxels])
    try:
        lattice = build_lattice(filled, robot.shape)
    except LatticeError as error:
        raise RobotError(f"voxels: {error}") from None
    voxel_k, voxel_offset, voxel_amp = _label_materials(robot.voxels, robot.sim, robot.actuation)
    spring, voxel = lattice.spring_voxels.T
    keep = lattice.kept[voxel]
    spring, voxel = spring[keep], voxel[keep]
    n = lattice.n_springs
    k = np.bincount(spring, weights=voxel_k[voxel], minlength=n)
    weighted_offset = np.bincount(spring, weights=voxel_k[voxel] * voxel_offset[voxel], minlength=n)
    weighted_amp = np.bincount(spring, weights=voxel_k[voxel] * voxel_amp[voxel], minlength=n)
    safe_k = np.where(k > 0, k, 1.0)
    if robot.phases is not None:
        return _phased_mechanics(robot, lattice, k, weighted_offset / safe_k, spring, voxel)
    return _labelled_mechanics(
        lattice, k, weighted_offset / safe_k, weighted_amp / safe_k, robot.actuation, robot.sim
    )


def _phased_mechanics(
    robot: VoxelRobot,
    lattice: Lattice,
    k: np.ndarray,
    offset: np.ndarray,
    spring: np.ndarray,
    voxel: np.ndarray,
) -> Mechanics:
    """Mechanics of a robot whose actuated voxels each have a phase and amplitude: voxel v's
    spring term k_v b_v sin(w t + c + phi_v) splits into sin(w t) and cos(w t) parts, summed
    over the voxels sharing the spring like the paper's single phase (same parallel rule)."""
    sim, n = robot.sim, lattice.n_springs
    sign = np.array([{"sine": 1.0, "neg_sine": -1.0}.get(v, 0.0) for v in robot.voxels])
    genes = np.full(len(sign), robot.actuation.b)
    if robot.amplitudes is not None:
        genes = np.asarray(robot.amplitudes, dtype=np.float64)
    stiffness = np.array([sim.actuated_stiffness if s else 0.0 for s in sign])
    amplitude = sim.amplitude_scale * sign * genes * stiffness
    phase = robot.actuation.c + np.asarray(robot.phases, dtype=np.float64)
    safe_k = np.where(k > 0, k, 1.0)
    length = lattice.spring_lengths * sim.edge_length
    part_sin = np.bincount(spring, weights=(amplitude * np.cos(phase))[voxel], minlength=n)
    part_cos = np.bincount(spring, weights=(amplitude * np.sin(phase))[voxel], minlength=n)
    return Mechanics(
        lattice=lattice,
        positions=_initial_positions(lattice, sim),
        stiffness=k,
        rest_length=length * (1.0 + offset),
        amp_sin=length * part_sin / safe_k,
        amp_cos=length * part_cos / safe_k,
        omega=sim.omega if np.any(amplitude != 0) else 0.0,
        sim=sim,
    )


def _labelled_mechanics(
    lattice: Lattice,
    k: np.ndarray,
    offset: np.ndarray,
    amplitude: np.ndarray,
    genes: Actuation,
    sim: SimSettings,
) -> Mechanics:
    """Mechanics from per-spring stiffness, relative offset and relative amplitude (phase c)."""
    length = lattice.spring_lengths * sim.edge_length
    amplitude = length * amplitude
    return Mechanics(
        lattice=lattice,
        positions=_initial_positions(lattice, sim),
        stiffness=k,
        rest_length=length * (1.0 + offset),
        amp_sin=amplitude * math.cos(genes.c),
        amp_cos=amplitude * math.sin(genes.c),
        omega=sim.omega if np.any(amplitude != 0) else 0.0,
        sim=sim,
    )


def _labelled_spring_mechanics(robot: LabelledSpringRobot) -> Mechanics:
    full = full_lattice(robot.shape)
    if len(robot.spring_labels) != full.n_springs:
        raise RobotError(
            f"spring_labels: expected {full.n_springs} labels (the springs of the full "
            f"{'x'.join(map(str, robot.shape))} lattice), got {len(robot.spring_labels)}"
        )
    for index, label in enumerate(robot.spring_labels):
        if label not in SPRING_LABELS:
            raise RobotError(
                f"spring_labels.{index}: unknown label {label!r} "
                f"(expected one of {', '.join(SPRING_LABELS)})"
            )
    try:
        lattice = build_lattice(np.array(robot.filled, dtype=bool), robot.shape)
    except LatticeError as error:
        raise RobotError(f"voxels: {error}") from None
    expressed = np.searchsorted(spring_point_keys(full), spring_point_keys(lattice))
    labels = tuple(robot.spring_labels[i] for i in expressed)
    k, offset, amplitude = _label_materials(labels, robot.sim, robot.actuation)
    return _labelled_mechanics(lattice, k, offset, amplitude, robot.actuation, robot.sim)


def _spring_mechanics(robot: SpringRobot) -> Mechanics:
    try:
        lattice = build_lattice(np.array(robot.filled, dtype=bool), robot.shape)
    except LatticeError as error:
        raise RobotError(f"voxels: {error}") from None
    options = np.asarray(robot.springs, dtype=np.float64)
    if options.shape != (lattice.n_springs, 4):
        raise RobotError(
            f"springs: expected {lattice.n_springs} entries of [k, b, w, c] (the springs of the "
            f"built lattice), got array of shape {list(options.shape)}"
        )
    k, b, w, c = options.T
    omegas = sorted(set(w[b != 0].tolist()))
    if len(omegas) > 1:
        raise RobotError(
            f"springs: actuated springs (b != 0) must share one frequency w, got {omegas}"
        )
    length = lattice.spring_lengths * robot.sim.edge_length
    return Mechanics(
        lattice=lattice,
        positions=_initial_positions(lattice, robot.sim),
        stiffness=k.copy(),
        rest_length=length.copy(),
        amp_sin=length * b * np.cos(c),
        amp_cos=length * b * np.sin(c),
        omega=omegas[0] if omegas else 0.0,
        sim=robot.sim,
    )


def dropped_voxels(robot: Robot, mechanics: Mechanics) -> int:
    """Filled voxels left out of `mechanics` because they are not face-connected to the
    largest group (only that group is built): worth telling whoever wrote the file."""
    if isinstance(robot, VoxelRobot):
        filled = sum(label != "empty" for label in robot.voxels)
    else:
        filled = sum(robot.filled)
    return int(filled - np.count_nonzero(mechanics.lattice.kept))


def build_mechanics(robot: Robot) -> Mechanics:
    """Turn a robot into the arrays the physics kernel runs on."""
    if isinstance(robot, VoxelRobot):
        return _voxel_mechanics(robot)
    if isinstance(robot, SpringRobot):
        return _spring_mechanics(robot)
    if isinstance(robot, LabelledSpringRobot):
        return _labelled_spring_mechanics(robot)
    raise TypeError(f"not a robot: {type(robot).__name__}")
