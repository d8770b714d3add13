"""The vxa against what evosoro's Voxelyze reads (skriegman/evosoro, `_voxcad/Voxelyze`; issue
40): its GA section and stop condition, GrowthAmplitude where that engine looks for it, the
per-voxel Structure layers in its layout, and each voxel's size rebuilt from the file with that
engine's rule (docs/export.md) equal to softevo's size 1 + offset + A sin(w t + phi).
bench/vxa_voxelyze.py runs the files in the engine itself; CI cannot build it."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from softevo.core.outputs.export import ExportError, export_robot
from softevo.core.robots.robot import Actuation, VoxelRobot
from softevo.core.robots.robot_file import load_robot
from softevo.core.robots.settings import sim_settings

#: The per-voxel layers that engine reads from the Structure (VX_Object.cpp), one Layer per z.
ENGINE_LAYERS = {
    "PhaseOffset",
    "FinalPhaseOffset",
    "TempAmpDamp",
    "FinalTempAmpDamp",
    "InitialVoxelSize",
    "FinalVoxelSize",
    "GrowthTime",
    "StartGrowthTime",
}
LABELS = ("sine", "hard", "neg_sine", "soft", "sine", "neg_sine")  # 3 x 2 x 1, x fastest


def parse(robot: VoxelRobot) -> ET.Element:
    return ET.fromstring(export_robot(robot, "vxa"))


def co_designed(**sim: float) -> VoxelRobot:
    """A voxel-phase robot with gene a: every actuated voxel its own phase and amplitude."""
    return VoxelRobot(
        (3, 2, 1),
        LABELS,
        Actuation(a=-0.6, b=0.9, c=0.4),
        sim_settings({"omega": 3.0, "duration": 6.0, "settle_time": 1.5, **sim}),
        phases=(0.3, 0.0, -1.2, 0.0, 2.0, 0.7),
        amplitudes=(1.1, 0.0, -0.5, 0.0, 0.2, 1.4),
    )


def layer_grid(structure: ET.Element, name: str) -> np.ndarray:
    """A per-voxel layer read as that engine does: per z, X*Y comma-separated numbers."""
    nx, ny, nz = (int(structure.findtext(f"{axis}_Voxels")) for axis in "XYZ")
    layers = [layer.text for layer in structure.findall(f"./{name}/Layer")]
    assert len(layers) == nz
    values = [[float(v) for v in layer.split(",")] for layer in layers]
    assert all(len(row) == nx * ny for row in values)
    return np.array(values).reshape(nz, ny, nx)


def engine_sizes(root: ET.Element, t: float) -> np.ndarray:
    """Every voxel's size at time t (edge lengths), by the rule of evosoro's Voxelyze
    (VXS_Voxel.cpp, docs/export.md): ramp k from InitCmTime over GrowthTime x (duration -
    InitCmTime); size = 1 + dev + damp x shrink x TempAmplitude x CTE x sin(2 pi (t / T + phi))."""
    structure = root.find("./VXC/Structure")
    env = root.find("Environment")
    stop = root.find("./Simulator/StopCondition")
    start, duration = float(stop.findtext("InitCmTime")), float(stop.findtext("StopConditionValue"))
    growth = float(env.findtext("GrowthAmplitude"))
    period = float(env.findtext("Thermal/TempPeriod"))
    amplitude = float(env.findtext("Thermal/TempAmplitude"))
    ids = np.array([[int(c) for c in layer.text] for layer in structure.findall("./Data/Layer")])
    ctes = {
        int(m.get("ID")): float(m.findtext("Mechanical/CTE"))
        for m in root.findall("./VXC/Palette/Material")
    }
    cte = np.vectorize(lambda i: ctes.get(i, 0.0))(ids).reshape(
        layer_grid(structure, "PhaseOffset").shape
    )
    phi = layer_grid(structure, "PhaseOffset")
    damp = layer_grid(structure, "TempAmpDamp")
    names = {child.tag for child in structure}
    k = 1.0
    if "GrowthTime" in names:
        k = min(
            max((t - start) / (layer_grid(structure, "GrowthTime") * (duration - start)).max(), 0),
            1,
        )
        damp = damp + k * (layer_grid(structure, "FinalTempAmpDamp") - damp)
    dev = np.zeros_like(phi)
    for name, ramp in (("FinalVoxelSize", k), ("InitialVoxelSize", 1.0)):
        if name in names:
            dev = ramp * growth * layer_grid(structure, name)
    shrink = (
        np.minimum(1 + dev / growth, 1) if names & {"FinalVoxelSize", "InitialVoxelSize"} else 1
    )
    wave = damp * shrink * amplitude * cte * np.sin(2 * math.pi * (t / period + phi))
    return np.where(ids.reshape(phi.shape) > 0, 1 + dev + (wave if t >= start else 0), 0)


def softevo_sizes(robot: VoxelRobot, t: float) -> np.ndarray:
    """softevo's voxel size 1 + offset_scale a + amplitude_scale sign b_v sin(w t + c + phi_v)."""
    sim, genes = robot.sim, robot.actuation
    sign = np.array([{"sine": 1.0, "neg_sine": -1.0}.get(label, 0.0) for label in robot.voxels])
    b = np.array(robot.amplitudes) if robot.amplitudes else np.full(len(sign), genes.b)
    phi = np.array(robot.phases) if robot.phases else np.zeros(len(sign))
    wave = sim.amplitude_scale * sign * b * np.sin(sim.omega * t + genes.c + phi)
    size = 1 + np.abs(sign) * (sim.offset_scale * genes.a + wave)
    size = np.where(np.array(robot.voxels) == "empty", 0.0, size)
    nx, ny, nz = robot.shape
    return size.reshape(nz, ny, nx)


def test_the_file_names_a_fitness_file_and_stops_at_softevos_duration() -> None:
    """Without a GA section naming the file, that engine writes no fitness file."""
    root = parse(co_designed())
    ga = root.find("./Simulator/GA")
    assert ga is not None and ga.findtext("WriteFitnessFile") == "1"
    assert ga.findtext("FitnessFileName").endswith(".xml")
    stop = root.find("./Simulator/StopCondition")
    assert stop.findtext("StopConditionType") == "2"  # SC_MAX_SIM_TIME
    assert float(stop.findtext("StopConditionValue")) == 6.0
    assert float(stop.findtext("InitCmTime")) == 0.0  # actuation from t = 0, as softevo's
    env = root.find("Environment")
    assert env.findtext("SaveTraces") == "1" and float(env.findtext("TimeBetweenTraces")) > 0


@pytest.mark.parametrize("settle", [1.5, 0.0])
def test_every_voxel_swings_as_in_softevo_once_the_ramp_is_over(settle: float) -> None:
    robot = co_designed(settle_time=settle)
    root = parse(robot)
    structure = root.find("./VXC/Structure")
    assert {child.tag for child in structure} - {"X_Voxels", "Y_Voxels", "Z_Voxels", "Data"} <= (
        ENGINE_LAYERS
    )
    assert root.find("./Environment/GrowthAmplitude") is not None  # read at Environment level
    for t in np.linspace(max(settle, 0.01), 6.0, 23):
        assert engine_sizes(root, t) == pytest.approx(softevo_sizes(robot, t), abs=1e-9)
    largest = max(engine_sizes(root, t).max() for t in np.linspace(0, 6, 301))
    assert largest <= 1 + float(root.findtext("./Environment/GrowthAmplitude"))  # never clamped


def test_the_ramp_starts_from_rest_and_lasts_the_settle_time() -> None:
    """No jolt: every voxel starts at its nominal size and changes no faster than softevo's
    swing plus the ramp (offset and amplitude over the settle time) allow; without a ramp (settle
    time 0) it jumps at once, as in softevo."""
    robot = co_designed()
    root = parse(robot)
    filled = engine_sizes(root, 0.0) > 0
    assert engine_sizes(root, 0.0)[filled] == pytest.approx(1.0)
    times = np.linspace(0, 1.5, 1501)
    sizes = np.array([engine_sizes(root, t)[filled] for t in times])
    rate = np.abs(np.diff(sizes, axis=0)).max() / (times[1] - times[0])
    assert rate <= 0.06 / 1.5 + 0.14 * (3.0 + 2 / 1.5)  # |offset| / ramp + |A| (w + 2 / ramp)
    at_once = parse(co_designed(settle_time=0.0))
    assert np.abs(engine_sizes(at_once, 0.0)[filled] - 1).max() > 0.05


def test_the_crawlers_voxels_may_grow_as_well_as_shrink(examples: Path) -> None:
    """GrowthAmplitude 0 caps every voxel at its nominal size: the crawler only shrank."""
    root = parse(load_robot(examples / "crawler_4x4x4.json"))
    growth = float(root.findtext("./Environment/GrowthAmplitude"))
    assert growth == pytest.approx(0.1 * 0.8657407322419473 + 0.1 * 1.0611836168618927, rel=1e-5)


def test_the_drop_height_is_empty_layers_under_the_robot(examples: Path) -> None:
    root = parse(load_robot(examples / "breathing_cube.json"))  # dropped from 1 m, 1 m voxels
    assert [layer.text for layer in root.findall("./VXC/Structure/Data/Layer")] == ["0", "3"]
    assert len(root.findall("./VXC/Structure/PhaseOffset/Layer")) == 2
    robot = co_designed(drop_height=0.4)  # not a whole number of layers: the nearest, said so
    text = export_robot(robot, "vxa").decode()
    assert "Voxelyze starts it on 0 empty layer(s)" in text
    tall = co_designed(drop_height=100.0, edge_length=0.01)  # 10000 layers: refused, one line
    with pytest.raises(ExportError, match=r"sim\.drop_height 100\.0 m is 10000 edge lengths"):
        export_robot(tall, "vxa")


def test_slow_damping_matches_softevos_velocity_factor() -> None:
    """softevo: v *= damping each dt, a rate -ln(damping)/dt; Voxelyze: 2 zeta sqrt(E L / M)."""
    robot = VoxelRobot((2, 1, 1), ("hard", "sine"), Actuation(0, 1, 0), sim_settings({}))
    root = parse(robot)
    zeta = float(root.findtext("./Simulator/Damping/SlowDampingZ"))
    modulus = float(root.findtext("./VXC/Palette/Material/Mechanical/Elastic_Mod"))  # soft
    hard = [float(m.findtext("Mechanical/Elastic_Mod")) for m in root.iter("Material")][1]
    mass = float(root.findtext("./VXC/Palette/Material/Mechanical/Density"))  # 1 m voxels
    assert modulus < hard
    assert 2 * zeta * math.sqrt(hard / mass) == pytest.approx(-math.log(0.99) / 0.0005)
    undamped = VoxelRobot((1, 1, 1), ("sine",), Actuation(0, 1, 0), sim_settings({"damping": 1.0}))
    assert float(parse(undamped).findtext("./Simulator/Damping/SlowDampingZ")) == 0.0
