"""A voxel robot as a `.vxa` file, the XML that Voxelyze, VoxCAD and voxcraft-sim read.

The layout is the one of the published examples (evosoro, voxcraft-sim): a VXA root with
Simulator, Environment and a VXC holding the Lattice, a Palette of Materials and the Structure,
whose Data has one CDATA Layer per z, each X*Y material indices, x fastest then y, 0 = empty.

softevo's springs and Voxelyze's beams are different models, so the mapping is first-order and
docs/export.md says where it is exact and where it is not:

* Elastic_Mod = (144/19) k / edge_length and Poissons_Ratio = 5/19: the small-strain Young's
  modulus and Poisson ratio, along a lattice axis, of a solid of softevo voxels whose springs
  have stiffness k (each voxel's 28 springs: C11 = 28/3 k/L, C12 = C44 = 10/3 k/L; derived in
  docs/export.md, checked against the lattice in tests/core/test_export.py). A lone Voxelyze bond
  E L matched to one spring would give E = k / L, 7.6 times softer than softevo's solid.
* Density = the robot's mass (softevo's point masses) over its voxels' volume: total mass kept.
* actuation: softevo's rest length L(1 + A sin(w t + c)) with A = amplitude_scale * b (negated
  for neg_sine) becomes Voxelyze's thermal expansion 1 + CTE * TempAmp * sin(2 pi (t /
  TempPeriod + MaterialTempPhase)) with TempAmp = 1, TempBase = 0, CTE = A,
  TempPeriod = 2 pi / w and MaterialTempPhase = c / (2 pi) (in periods). Exact in kind; gene a
  (a constant rest-length offset) has no Voxelyze equivalent and is left out.
"""

from __future__ import annotations

import math
from xml.sax.saxutils import escape

import numpy as np

from softevo.core.export import COLOURS, ExportError
from softevo.core.robot import ACTUATED_LABELS, Robot, VoxelRobot
from softevo.core.settings import SimSettings

#: Palette order: the material index of each label in the Structure's Data (0 = empty).
MATERIAL_IDS = {"soft": 1, "hard": 2, "sine": 3, "neg_sine": 4}
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


def material_table(robot: VoxelRobot, n_masses: int, n_voxels: int) -> dict[str, dict[str, float]]:
    """Per label: Elastic_Mod, Density, CTE and MaterialTempPhase of its Voxelyze material."""
    sim = robot.sim
    density = n_masses * sim.mass / (n_voxels * sim.edge_length**3)
    amplitude = sim.amplitude_scale * robot.actuation.b if sim.omega > 0 else 0.0
    phase = (robot.actuation.c / (2 * math.pi)) % 1.0
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


def _simulator(xml: _Xml, sim: SimSettings) -> None:
    xml.open("Simulator")
    xml.comment(
        "Voxelyze picks its own stable time step (DtFrac); softevo's dt = "
        f"{_number(sim.dt)} s and its velocity damping factor {_number(sim.damping)} per step "
        "have no Voxelyze equivalent, the damping below is the published examples' default"
    )
    xml.open("Integration")
    xml.leaf("Integrator", 0)
    xml.leaf("DtFrac", 0.95)
    xml.close("Integration")
    xml.open("Damping")
    xml.leaf("BondDampingZ", 1.0)
    xml.leaf("ColDampingZ", 0.8)
    xml.leaf("SlowDampingZ", 0.01)
    xml.close("Damping")
    xml.open("StopCondition")
    xml.leaf("StopConditionType", 2)  # Voxelyze 1 / VoxCAD: stop after a simulated time
    xml.leaf("StopConditionValue", sim.duration)
    xml.leaf("InitCmTime", sim.settle_time)  # the fitness clock starts after settling
    xml.open("StopConditionFormula")  # voxcraft-sim: stop when t - duration > 0
    xml.open("mtSUB")
    xml.leaf("mtVAR", "t")
    xml.leaf("mtCONST", sim.duration)
    xml.close("mtSUB")
    xml.close("StopConditionFormula")
    xml.close("StopCondition")
    xml.close("Simulator")


def _environment(xml: _Xml, sim: SimSettings) -> None:
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


def to_vxa(robot: Robot, grid: np.ndarray) -> bytes:
    """`robot` (its simulated voxels `grid`, see softevo.core.export.voxel_grid) as a VXA."""
    if not isinstance(robot, VoxelRobot):
        raise ExportError(
            "vxa needs a robot of voxel materials (soft, hard, sine, neg_sine): this robot's "
            "springs carry their own materials, which Voxelyze cannot express (use glb or stl)"
        )
    if robot.phases is not None:
        raise ExportError(
            "vxa: this robot's voxels each have their own phase and amplitude (voxel-phase), "
            "which Voxelyze's per-material actuation cannot express (use glb or stl)"
        )
    filled = grid != "empty"
    table = material_table(robot, _corner_count(filled), int(filled.sum()))
    sim = robot.sim
    xml = _Xml()
    xml.open("VXA", Version="1.1")
    xml.comment(
        "written by softevo from a softevo.robot/1 file; the mapping of its "
        "springs to Voxelyze materials is first-order (softevo docs/export.md)"
    )
    if robot.actuation.a != 0:
        xml.comment(
            f"actuation gene a = {_number(robot.actuation.a)} (a constant rest-length offset of "
            "the actuated voxels) has no Voxelyze equivalent and is left out"
        )
    _simulator(xml, sim)
    _environment(xml, sim)
    xml.open("VXC", Version="0.94")
    xml.open("Lattice")
    xml.leaf("Lattice_Dim", sim.edge_length)
    xml.close("Lattice")
    xml.open("Voxel")
    xml.leaf("Vox_Name", "BOX")
    xml.close("Voxel")
    _palette(xml, table, sim)
    xml.open("Structure", Compression="ASCII_READABLE")
    nx, ny, nz = grid.shape
    xml.leaf("X_Voxels", nx)
    xml.leaf("Y_Voxels", ny)
    xml.leaf("Z_Voxels", nz)
    xml.open("Data")
    for layer in layers(grid):
        xml.cdata("Layer", layer)
    xml.close("Data")
    xml.close("Structure")
    xml.close("VXC")
    xml.close("VXA")
    return xml.text()
