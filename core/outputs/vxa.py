"""A voxel robot as a `.vxa` file, the XML that Voxelyze, VoxCAD and voxcraft-sim read.

The layout is the one of the published examples (evosoro, voxcraft-sim): a VXA root with
Simulator, Environment and a VXC holding the Lattice, a Palette of Materials and the Structure,
whose Data has one CDATA Layer per z, each X*Y material indices, x fastest then y, 0 = empty.

softevo's springs and Voxelyze's beams are different models, so the mapping is first-order and
docs/export.md says where it is exact and where it is not:

* Elastic_Mod = (144/19) k / edge_length and Poissons_Ratio = 5/19: the small-strain Young's
  modulus and Poisson ratio, along a lattice axis, of a solid of softevo voxels whose springs
  have stiffness k (each voxel's 28 springs: C11 = 28/3 k/L, C12 = C44 = 10/3 k/L; derived in
  docs/export.md, checked against the lattice in tests/core/outputs/test_export.py). A lone
  Voxelyze bond
  E L matched to one spring would give E = k / L, 7.6 times softer than softevo's solid.
* Density = the robot's mass (softevo's point masses) over its voxels' volume: total mass kept.
* actuation: softevo's voxel size 1 + offset + A sin(w t + phi), per voxel, becomes the size
  that evosoro's Voxelyze gives it from its CTE, TempPeriod = 2 pi / w and the per-voxel layers
  PhaseOffset, TempAmpDamp, FinalTempAmpDamp, GrowthTime and Final/InitialVoxelSize
  (softevo.core.outputs.vxa_layers), ramped in over softevo's settle time; GrowthAmplitude lets a
  voxel grow as well as shrink.
* the run: a GA section (the fitness file, with the centre of mass traced), a stop at softevo's
  duration, the drop height as empty layers under the robot, softevo's velocity damping as
  SlowDampingZ.
"""

from __future__ import annotations

import math
from xml.sax.saxutils import escape

import numpy as np

from softevo.core.outputs.vxa_layers import (
    VoxelActuation,
    drop_layers,
    slow_damping,
    structure_layers,
    voxel_actuation,
)
from softevo.core.robots.robot import ACTUATED_LABELS, COLOURS, Robot, VoxelRobot
from softevo.core.robots.settings import SimSettings

#: Palette order: the material index of each label in the Structure's Data (0 = empty).
MATERIAL_IDS = {"soft": 1, "hard": 2, "sine": 3, "neg_sine": 4}
#: The fitness file's name in the GA section: Voxelyze writes it in its working folder.
FITNESS_FILE = "softevo_fitness.xml"
#: CM trace points in the fitness file per actuation period (or per duration without actuation).
TRACES_PER_PERIOD = 50
#: Most empty layers written under a robot for its drop height (each is X*Y numbers per layer).
MAX_DROP_LAYERS = 1000
#: Voxelyze's bond damping ratio (1 = critical) for a robot whose springs are undamped (the paper
#: profile): the published examples' value, which the engine needs to stay stable; a robot with
#: `material_damping` exports that ratio instead (docs/export.md).
BOND_DAMPING_Z = 1.0
#: Voxelyze's floor damping ratio for a robot without `contact_damping`: evosoro's value.
COL_DAMPING_Z = 0.8
#: Names given to the materials, in the style of the published examples.
MATERIAL_NAMES = {
    "soft": "Passive_Soft",
    "hard": "Passive_Hard",
    "sine": "Active_+",
    "neg_sine": "Active_-",
}
#: Elastic constants of a solid of softevo voxels, in units of k / edge_length (docs/export.md).
C11, C12 = 28 / 3, 10 / 3
#: Its Young's modulus along a lattice axis (144/19 k/L) and Poisson ratio (5/19) from them.
YOUNGS_PER_SPRING = (C11 - C12) * (C11 + 2 * C12) / (C11 + C12)
POISSONS_RATIO = C12 / (C11 + C12)


def _number(value: float) -> str:
    """Shortest text that reads back as the same float (no locale, no rounding)."""
    return repr(float(value))


class _Xml:
    """A tiny indenting XML writer: every name and text here is softevo's own, escaped anyway."""

    def __init__(self) -> None:
        self.lines: list[str] = ['<?xml version="1.0" encoding="UTF-8"?>']
        self.depth = 0

    def open(self, tag: str, **attributes: str) -> None:
        attrs = "".join(f' {name}="{escape(value)}"' for name, value in attributes.items())
        self.lines.append(f"{'  ' * self.depth}<{tag}{attrs}>")
        self.depth += 1

    def close(self, tag: str) -> None:
        self.depth -= 1
        self.lines.append(f"{'  ' * self.depth}</{tag}>")

    def leaf(self, tag: str, text: str | float | int) -> None:
        value = _number(text) if isinstance(text, float) else escape(str(text))
        self.lines.append(f"{'  ' * self.depth}<{tag}>{value}</{tag}>")

    def cdata(self, tag: str, text: str) -> None:
        self.lines.append(f"{'  ' * self.depth}<{tag}><![CDATA[{text}]]></{tag}>")

    def comment(self, text: str) -> None:
        self.lines.append(f"{'  ' * self.depth}<!-- {escape(text).replace('--', '- -')} -->")

    def text(self) -> bytes:
        return ("\n".join(self.lines) + "\n").encode("utf-8")


def elastic_modulus(stiffness: float, edge_length: float) -> float:
    """Voxelyze's Elastic_Mod (Pa): the Young's modulus of a solid of softevo voxels whose
    springs all have `stiffness` (N/m), so a block stretches alike in both simulators."""
    return YOUNGS_PER_SPRING * stiffness / edge_length


def material_table(
    robot: VoxelRobot, actuation: VoxelActuation, n_masses: int, n_voxels: int
) -> dict[str, dict[str, float]]:
    """Per label: Elastic_Mod, Density, CTE and MaterialTempPhase of its Voxelyze material."""
    sim = robot.sim
    density = n_masses * sim.mass / (n_voxels * sim.edge_length**3)
    amplitude = actuation.cte if sim.omega > 0 else 0.0
    phase = robot.actuation.c % (2 * math.pi)  # radians, as Voxelyze's UpdateCurTemp adds it
    stiffness = {
        "soft": sim.soft_stiffness,
        "hard": sim.hard_stiffness,
        "sine": sim.actuated_stiffness,
        "neg_sine": sim.actuated_stiffness,
    }
    cte = {"soft": 0.0, "hard": 0.0, "sine": amplitude, "neg_sine": -amplitude}
    return {
        label: {
            "Elastic_Mod": elastic_modulus(stiffness[label], sim.edge_length),
            "Density": density,
            "CTE": cte[label],
            "MaterialTempPhase": phase if label in ACTUATED_LABELS else 0.0,
        }
        for label in MATERIAL_IDS
    }


def _simulator(xml: _Xml, sim: SimSettings, slow_damping_z: float) -> None:
    xml.open("Simulator")
    xml.comment(
        f"Voxelyze picks its own stable time step (DtFrac); softevo's dt = {_number(sim.step)} s. "
        f"SlowDampingZ matches softevo's velocity factor {_number(sim.velocity_factor)} per step"
    )
    xml.open("Integration")
    xml.leaf("Integrator", 0)
    xml.leaf("DtFrac", 0.95)
    xml.close("Integration")
    xml.open("Damping")
    xml.leaf("BondDampingZ", sim.material_damping or BOND_DAMPING_Z)
    xml.leaf("ColDampingZ", sim.contact_damping or COL_DAMPING_Z)
    xml.leaf("SlowDampingZ", slow_damping_z)
    xml.close("Damping")
    xml.open("StopCondition")
    xml.leaf("StopConditionType", 2)  # SC_MAX_SIM_TIME: stop after a simulated time
    xml.leaf("StopConditionValue", sim.duration)
    xml.comment(
        "evosoro's Voxelyze starts actuation and its fitness clock at InitCmTime: 0 here, so "
        "the voxels swing in phase with softevo's clock; softevo's fitness clock starts at "
        f"{_number(sim.settle_time)} s (settle_time): take it from the fitness file's CMTrace"
    )
    xml.leaf("InitCmTime", 0.0)
    xml.open("StopConditionFormula")  # voxcraft-sim: stop when t - duration > 0
    xml.open("mtSUB")
    xml.leaf("mtVAR", "t")
    xml.leaf("mtCONST", sim.duration)
    xml.close("mtSUB")
    xml.close("StopConditionFormula")
    xml.close("StopCondition")
    xml.open("GA")  # evosoro's Voxelyze writes its fitness file only with a name
    xml.leaf("WriteFitnessFile", 1)
    xml.leaf("FitnessFileName", FITNESS_FILE)
    xml.close("GA")
    xml.close("Simulator")


def _environment(xml: _Xml, sim: SimSettings, growth_amplitude: float) -> None:
    actuated = sim.omega > 0
    xml.open("Environment")
    xml.open("Fixed_Regions")
    xml.leaf("NumFixed", 0)
    xml.close("Fixed_Regions")
    xml.open("Forced_Regions")
    xml.leaf("NumForced", 0)
    xml.close("Forced_Regions")
    xml.open("Gravity")
    xml.leaf("GravEnabled", int(sim.gravity != 0))
    xml.leaf("GravAcc", sim.gravity)
    if sim.terrain.kind != "flat":
        xml.comment(f"softevo's {sim.terrain.kind} terrain is not exported: the floor is flat")
    xml.leaf("FloorEnabled", 1)
    xml.close("Gravity")
    xml.open("Thermal")
    xml.leaf("TempEnabled", int(actuated))
    xml.leaf("TempAmp", 1.0)  # Voxelyze 1 / VoxCAD
    xml.leaf("TempAmplitude", 1.0)  # voxcraft-sim
    xml.leaf("TempBase", 0.0)
    xml.leaf("VaryTempEnabled", int(actuated))
    xml.leaf("TempPeriod", 2 * math.pi / sim.omega if actuated else 0.0)
    xml.close("Thermal")
    xml.comment("the largest size a voxel may take is 1 + GrowthAmplitude (0: voxels only shrink)")
    xml.leaf("GrowthAmplitude", growth_amplitude)
    xml.leaf("SaveTraces", 1)  # the centre of mass over time, in the fitness file
    span = 2 * math.pi / sim.omega if actuated else sim.duration
    xml.leaf("TimeBetweenTraces", min(span, sim.duration) / TRACES_PER_PERIOD)
    xml.close("Environment")


def _palette(xml: _Xml, table: dict[str, dict[str, float]], sim: SimSettings) -> None:
    xml.open("Palette")
    for label, material_id in MATERIAL_IDS.items():
        xml.open("Material", ID=str(material_id))
        xml.leaf("MatType", 0)
        xml.leaf("Name", MATERIAL_NAMES[label])
        xml.open("Display")
        for channel, value in zip(("Red", "Green", "Blue"), COLOURS[label], strict=True):
            xml.leaf(channel, round(value / 255, 4))
        xml.leaf("Alpha", 1.0)
        xml.close("Display")
        xml.open("Mechanical")
        xml.leaf("MatModel", 0)  # linear elastic, never fails
        properties = table[label]
        xml.leaf("Elastic_Mod", properties["Elastic_Mod"])
        xml.leaf("Plastic_Mod", 0.0)
        xml.leaf("Yield_Stress", 0.0)
        xml.leaf("FailModel", 0)
        xml.leaf("Fail_Stress", 0.0)
        xml.leaf("Fail_Strain", 0.0)
        xml.leaf("Density", properties["Density"])
        xml.leaf("Poissons_Ratio", POISSONS_RATIO)
        xml.leaf("CTE", properties["CTE"])
        xml.leaf("MaterialTempPhase", properties["MaterialTempPhase"])
        xml.leaf("uStatic", sim.friction)  # softevo's one Coulomb coefficient for both
        xml.leaf("uDynamic", sim.friction)
        xml.close("Mechanical")
        xml.close("Material")
    xml.close("Palette")


def layers(grid: np.ndarray) -> list[str]:
    """The Structure's Data: per z, the material index of every (x, y), x fastest then y."""
    ids = np.vectorize(lambda label: MATERIAL_IDS.get(label, 0), otypes=[np.int64])(grid)
    return ["".join(str(i) for i in ids[:, :, z].T.ravel()) for z in range(grid.shape[2])]


def _corner_count(filled: np.ndarray) -> int:
    """The lattice points (softevo's masses) of the filled voxels of a grid [x, y, z]."""
    cells = np.argwhere(filled)
    offsets = np.array([(i & 1, (i >> 1) & 1, (i >> 2) & 1) for i in range(8)])
    return len(np.unique((cells[:, None, :] + offsets[None]).reshape(-1, 3), axis=0))


def value_layers(values: np.ndarray) -> list[str]:
    """A per-voxel layer (PhaseOffset, ...): per z, comma-separated numbers of every (x, y), x
    fastest then y, as evosoro's Voxelyze splits them (it reads those of filled voxels only)."""
    return [",".join(_number(v) for v in values[:, :, z].T.ravel()) for z in range(values.shape[2])]


def _structure(xml: _Xml, grid: np.ndarray, per_voxel: dict[str, np.ndarray]) -> None:
    xml.open("Structure", Compression="ASCII_READABLE")
    nx, ny, nz = grid.shape
    xml.leaf("X_Voxels", nx)
    xml.leaf("Y_Voxels", ny)
    xml.leaf("Z_Voxels", nz)
    xml.open("Data")
    for layer in layers(grid):
        xml.cdata("Layer", layer)
    xml.close("Data")
    for name, values in per_voxel.items():
        xml.open(name)
        for layer in value_layers(values):
            xml.cdata("Layer", layer)
        xml.close(name)
    xml.close("Structure")


def _lifted(grid: np.ndarray, below: int) -> np.ndarray:
    """`grid` with `below` empty layers under it (the drop height): "empty" or 0 in them."""
    fill = "empty" if grid.dtype == object else 0.0
    return np.pad(grid, ((0, 0), (0, 0), (below, 0)), constant_values=fill)


class VxaError(ValueError):
    """A robot that a VXA cannot express; the message is one line (`export_robot` says it as
    an `ExportError`, as `voxel_grid` says a `LatticeError`)."""


def to_vxa(robot: Robot, grid: np.ndarray) -> bytes:
    """`robot` (its simulated voxels `grid`, see softevo.core.outputs.export.voxel_grid) as a VXA
    that evosoro's Voxelyze runs as it is, writing its fitness file (docs/export.md)."""
    if not isinstance(robot, VoxelRobot):
        raise VxaError(
            "vxa needs a robot of voxel materials (soft, hard, sine, neg_sine): this robot's "
            "springs carry their own materials, which Voxelyze cannot express (use glb or stl)"
        )
    filled = grid != "empty"
    actuation = voxel_actuation(robot, grid)
    table = material_table(robot, actuation, _corner_count(filled), int(filled.sum()))
    sim = robot.sim
    moduli = np.array([table[label]["Elastic_Mod"] for label in grid[filled]])
    voxel_mass = table["soft"]["Density"] * sim.edge_length**3
    below = drop_layers(robot)
    if below > MAX_DROP_LAYERS:
        raise VxaError(
            f"vxa: sim.drop_height {_number(sim.drop_height)} m is {below} edge lengths, written "
            f"as that many empty layers under the robot: more than {MAX_DROP_LAYERS}"
        )
    xml = _Xml()
    xml.open("VXA", Version="1.1")
    xml.comment(
        "written by softevo from a softevo.robot/1 file; the mapping of its "
        "springs to Voxelyze materials is first-order (softevo docs/export.md)"
    )
    if abs(below * sim.edge_length - sim.drop_height) > 1e-9 * sim.edge_length:
        xml.comment(
            f"softevo drops this robot from {_number(sim.drop_height)} m; Voxelyze starts it on "
            f"{below} empty layer(s), {_number(below * sim.edge_length)} m up"
        )
    _simulator(xml, sim, slow_damping(robot, moduli, voxel_mass))
    _environment(xml, sim, actuation.growth_amplitude if actuation.actuated else 0.0)
    xml.open("VXC", Version="0.94")
    xml.open("Lattice")
    xml.leaf("Lattice_Dim", sim.edge_length)
    xml.close("Lattice")
    xml.open("Voxel")
    xml.leaf("Vox_Name", "BOX")
    xml.close("Voxel")
    _palette(xml, table, sim)
    per_voxel = structure_layers(actuation, sim.duration)
    _structure(xml, _lifted(grid, below), {k: _lifted(v, below) for k, v in per_voxel.items()})
    xml.close("VXC")
    xml.close("VXA")
    return xml.text()
