"""Exported robots read back by other tools' parsers: the .vxa by xml.etree with the layout of
the published Voxelyze / voxcraft-sim examples and softevo's numbers in it, the .glb and .stl
by trimesh with the robot's volume, bounding box and a closed surface."""

from __future__ import annotations

import io
import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import trimesh

from softevo.core.outputs.export import (
    FORMATS,
    Z_UP_TO_Y_UP,
    ExportError,
    export_robot,
    format_from_path,
    linear_rgb,
    surface_faces,
    voxel_grid,
)
from softevo.core.robots.lattice import build_lattice
from softevo.core.robots.robot import COLOURS, Actuation, VoxelRobot, build_mechanics
from softevo.core.robots.robot_file import load_robot
from softevo.core.robots.settings import sim_settings

#: 3 x 2 x 2, every material, one empty corner; labels x fastest, then y, then z.
MIXED = (
    "soft",
    "hard",
    "sine",
    "neg_sine",
    "soft",
    "empty",
    "hard",
    "hard",
    "sine",
    "soft",
    "neg_sine",
    "hard",
)
SIM = {"edge_length": 0.5, "omega": 4.0, "friction": 0.7, "mass": 0.2, "soft_stiffness": 600.0}


def mixed_robot(**sim: Any) -> VoxelRobot:
    return VoxelRobot(
        (3, 2, 2), MIXED, Actuation(a=0.3, b=1.2, c=-1.0), sim_settings({**SIM, **sim})
    )


def parse_vxa(robot: VoxelRobot) -> ET.Element:
    return ET.fromstring(export_robot(robot, "vxa"))


def materials(root: ET.Element) -> dict[str, ET.Element]:
    """Material elements of the palette by their Name."""
    return {m.findtext("Name"): m for m in root.findall("./VXC/Palette/Material")}


def mechanical(root: ET.Element, name: str, field: str) -> float:
    return float(materials(root)[name].findtext(f"Mechanical/{field}"))


def test_vxa_has_the_published_layout_and_the_robots_voxels() -> None:
    root = parse_vxa(mixed_robot())
    assert root.tag == "VXA" and root.get("Version") == "1.1"
    assert [child.tag for child in root] == ["Simulator", "Environment", "VXC"]
    palette = root.findall("./VXC/Palette/Material")
    assert [m.get("ID") for m in palette] == ["1", "2", "3", "4"]
    assert all(m.find("Mechanical/Elastic_Mod") is not None for m in palette)
    structure = root.find("./VXC/Structure")
    assert structure.get("Compression") == "ASCII_READABLE"
    dims = [int(structure.findtext(f"{axis}_Voxels")) for axis in "XYZ"]
    assert dims == [3, 2, 2]
    layers = [layer.text for layer in structure.findall("./Data/Layer")]
    assert len(layers) == 2 and all(len(layer) == 3 * 2 and layer.isdigit() for layer in layers)
    index = {"empty": 0, "soft": 1, "hard": 2, "sine": 3, "neg_sine": 4}
    names = {m.get("ID"): m.findtext("Name") for m in palette}
    assert names == {"1": "Passive_Soft", "2": "Passive_Hard", "3": "Active_+", "4": "Active_-"}
    read = [int(layers[z][y * 3 + x]) for z in range(2) for y in range(2) for x in range(3)]
    assert read == [index[label] for label in MIXED]  # x fastest, then y, one layer per z


def test_vxa_layers_are_cdata_in_the_file() -> None:
    text = export_robot(mixed_robot(), "vxa").decode()
    assert "<Layer><![CDATA[123410]]></Layer>" in text  # z = 0: row y = 0, then row y = 1
    assert "<Layer><![CDATA[223142]]></Layer>" in text


def test_vxa_maps_stiffness_mass_actuation_and_friction() -> None:
    robot = mixed_robot()
    sim = robot.sim
    root = parse_vxa(robot)
    assert float(root.findtext("./VXC/Lattice/Lattice_Dim")) == 0.5
    assert mechanical(root, "Passive_Soft", "Elastic_Mod") == pytest.approx(144 / 19 * 600 / 0.5)
    assert mechanical(root, "Passive_Hard", "Elastic_Mod") == pytest.approx(144 / 19 * 2000 / 0.5)
    assert mechanical(root, "Active_+", "Elastic_Mod") == pytest.approx(144 / 19 * 2000 / 0.5)
    assert mechanical(root, "Active_+", "Poissons_Ratio") == pytest.approx(5 / 19)
    thermal = root.find("./Environment/Thermal")
    assert float(thermal.findtext("TempPeriod")) == pytest.approx(2 * math.pi / 4.0)
    assert float(thermal.findtext("TempAmp")) == float(thermal.findtext("TempAmplitude")) == 1.0
    assert float(thermal.findtext("TempBase")) == 0.0
    assert mechanical(root, "Active_+", "CTE") == pytest.approx(sim.amplitude_scale * 1.2)
    assert mechanical(root, "Active_-", "CTE") == pytest.approx(-sim.amplitude_scale * 1.2)
    assert mechanical(root, "Passive_Soft", "CTE") == 0.0
    # MaterialTempPhase in radians, as evosoro's Voxelyze adds it (UpdateCurTemp)
    assert mechanical(root, "Active_+", "MaterialTempPhase") == pytest.approx(2 * math.pi - 1.0)
    # the voxels' own phase, in periods: sin(w t + c) == sin(2 pi (t / TempPeriod + phase))
    phase = float(root.findtext("./VXC/Structure/PhaseOffset/Layer").split(",")[2])
    period = float(thermal.findtext("TempPeriod"))
    for t in (0.0, 0.3, 1.7):
        expected = math.sin(4.0 * t - 1.0)
        assert math.sin(2 * math.pi * (t / period + phase)) == pytest.approx(expected)
    # the whole robot's mass is kept: Density x volume of its voxels = softevo's point masses
    filled = np.array([label != "empty" for label in MIXED])
    masses = build_lattice(filled, robot.shape).n_masses
    density = mechanical(root, "Passive_Hard", "Density")
    assert density * 11 * 0.5**3 == pytest.approx(masses * 0.2)
    assert mechanical(root, "Active_-", "uStatic") == mechanical(root, "Active_-", "uDynamic")
    assert mechanical(root, "Active_-", "uStatic") == 0.7
    gravity = root.find("./Environment/Gravity")
    assert float(gravity.findtext("GravAcc")) == -9.81
    stop = root.find("./Simulator/StopCondition")
    assert float(stop.findtext("StopConditionValue")) == sim.duration


def test_elastic_mod_is_the_young_modulus_of_softevos_solid() -> None:
    """Stretch a block of soft voxels uniformly, in the robot's own lattice and springs: its
    energy gives C11 and C12, hence Young's modulus and Poisson ratio, which the vxa writes."""
    robot = VoxelRobot((3, 2, 2), ("soft",) * 12, sim=sim_settings(SIM))
    mechanics = build_mechanics(robot)
    rest, (first, second) = mechanics.positions, mechanics.lattice.springs.T
    length = np.linalg.norm(rest[first] - rest[second], axis=1)

    def energy_density(strain: np.ndarray) -> float:
        moved = rest @ (np.eye(3) + strain).T
        stretch = np.linalg.norm(moved[first] - moved[second], axis=1) - length
        return 0.5 * float(np.sum(mechanics.stiffness * stretch**2)) / (12 * 0.5**3)

    small = 1e-6
    c11 = 2 * energy_density(np.diag([small, 0, 0])) / small**2
    c12 = (2 * energy_density(np.diag([small, small, 0])) / small**2 - 2 * c11) / 2
    young = (c11 - c12) * (c11 + 2 * c12) / (c11 + c12)
    root = parse_vxa(robot)
    assert mechanical(root, "Passive_Soft", "Elastic_Mod") == pytest.approx(young, rel=1e-4)
    assert mechanical(root, "Passive_Soft", "Poissons_Ratio") == pytest.approx(
        c12 / (c11 + c12), rel=1e-4
    )


def test_vxa_without_actuation_turns_the_temperature_off() -> None:
    root = parse_vxa(mixed_robot(omega=0.0))
    assert root.findtext("./Environment/Thermal/VaryTempEnabled") == "0"
    assert mechanical(root, "Active_+", "CTE") == 0.0


def test_vxa_leaves_out_voxels_the_lattice_drops() -> None:
    """A voxel touching the robot only at a corner is not simulated, so not exported."""
    voxels = ["hard", "empty", "empty", "empty", "empty", "empty", "empty", "soft"]
    robot = VoxelRobot((2, 2, 2), tuple(voxels), sim=sim_settings({}))
    layers = [layer.text for layer in parse_vxa(robot).iter("Layer")]
    assert layers == ["2000", "0000"]


def test_vxa_refuses_robots_whose_springs_carry_the_materials(examples: Path) -> None:
    robot = load_robot(examples / "paper_cube.json")
    with pytest.raises(ExportError, match="vxa needs a robot of voxel materials"):
        export_robot(robot, "vxa")


def test_vxa_glb_and_stl_export_a_co_designed_robot() -> None:
    """voxel-phase robots were refused; their phases now go to Voxelyze's PhaseOffset layer."""
    labels = ("sine", "hard", "neg_sine", "soft")
    robot = VoxelRobot(
        (4, 1, 1),
        labels,
        Actuation(0.1, 0.5, 0.0),
        sim_settings({}),
        (0.0, 0.0, 1.0, 0.0),
        (0.5, 0.0, 0.5, 0.0),
    )
    for name in ("vxa", "glb", "stl"):
        assert len(export_robot(robot, name)) > 100


def test_unknown_format_is_refused_naming_the_formats() -> None:
    with pytest.raises(ExportError, match="vxa, glb, stl"):
        export_robot(mixed_robot(), "obj")


def test_format_from_path() -> None:
    assert [format_from_path(f"r.{f}") for f in FORMATS] == list(FORMATS)
    assert format_from_path("ROBOT.GLB") == "glb"
    assert format_from_path("robot.json") is None and format_from_path("robot") is None


def test_surface_has_only_the_outer_faces() -> None:
    assert len(surface_faces(np.ones((1, 1, 1), dtype=bool))[0]) == 6
    assert len(surface_faces(np.ones((2, 1, 1), dtype=bool))[0]) == 10  # the shared face: none
    assert len(surface_faces(np.ones((3, 3, 3), dtype=bool))[0]) == 6 * 9


def load_stl(robot: Any) -> trimesh.Trimesh:
    return trimesh.load(io.BytesIO(export_robot(robot, "stl")), file_type="stl")


def load_glb(robot: Any) -> trimesh.Scene:
    return trimesh.load(io.BytesIO(export_robot(robot, "glb")), file_type="glb")


def expected_box(robot: Any) -> tuple[int, np.ndarray]:
    """Filled voxels and their bounding box (metres, +Z up) from the robot's own grid."""
    cells = np.argwhere(voxel_grid(robot) != "empty")
    box = np.array([cells.min(axis=0), cells.max(axis=0) + 1]) * robot.sim.edge_length
    return len(cells), box


@pytest.mark.parametrize("name", ["mixed", "crawler_4x4x4.json", "paper_cube.json"])
def test_stl_volume_box_and_closed_surface(name: str, examples: Path) -> None:
    robot = mixed_robot() if name == "mixed" else load_robot(examples / name)
    mesh = load_stl(robot)
    count, box = expected_box(robot)
    assert mesh.volume == pytest.approx(count * robot.sim.edge_length**3)
    np.testing.assert_allclose(mesh.bounds, box)
    assert mesh.is_winding_consistent and mesh.volume > 0  # outward normals
    _, uses = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
    assert set(uses.tolist()) <= {2, 4}  # closed: no edge of one face (4: voxels meet at an edge)
    if name != "crawler_4x4x4.json":  # its voxels meet at bare edges in 6 places (docs/export.md)
        assert mesh.is_watertight


def test_stl_of_voxels_meeting_at_an_edge_keeps_its_volume() -> None:
    """(0,0,0) and (1,1,0) touch along an edge only (joined by the layer above): the surface is
    closed but not a manifold there; the volume is still exact."""
    voxels = ["soft", "empty", "empty", "soft", "soft", "soft", "empty", "soft"]
    robot = VoxelRobot((2, 2, 2), tuple(voxels), sim=sim_settings({"edge_length": 0.1}))
    mesh = load_stl(robot)
    assert mesh.volume == pytest.approx(5 * 0.1**3)
    _, uses = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
    assert sorted(set(uses.tolist())) == [2, 4] and not mesh.is_watertight


def test_glb_meshes_per_material_volume_box_and_colours() -> None:
    robot = mixed_robot()
    scene = load_glb(robot)
    assert sorted(scene.geometry) == ["hard", "neg_sine", "sine", "soft"]
    for label, mesh in scene.geometry.items():  # glTF colours are linear: sRGB decoded
        colour = np.asarray(mesh.visual.material.baseColorFactor[:3]) / 255
        np.testing.assert_allclose(colour, linear_rgb(COLOURS[label]), atol=1 / 255)
    assert linear_rgb((255, 0, 188)) == pytest.approx([1.0, 0.0, 0.503], abs=1e-3)
    whole = scene.to_mesh()
    whole.merge_vertices(merge_tex=True, merge_norm=True)  # one vertex per corner
    count, box = expected_box(robot)
    assert whole.volume == pytest.approx(count * 0.5**3)
    assert whole.is_watertight and whole.is_winding_consistent
    z_up = whole.vertices @ Z_UP_TO_Y_UP  # glTF's +Y up back to softevo's +Z up
    np.testing.assert_allclose([z_up.min(axis=0), z_up.max(axis=0)], box, atol=1e-12)
    assert whole.bounds[1][1] == pytest.approx(box[1][2])  # height is glTF's y


def test_glb_of_a_robot_without_voxel_materials_is_one_filled_mesh(examples: Path) -> None:
    robot = load_robot(examples / "paper_cube.json")
    scene = load_glb(robot)
    assert list(scene.geometry) == ["filled"]
    assert scene.to_mesh().volume == pytest.approx(robot.sim.edge_length**3)


def test_exports_are_deterministic() -> None:
    for format in FORMATS:
        assert export_robot(mixed_robot(), format) == export_robot(mixed_robot(), format)
