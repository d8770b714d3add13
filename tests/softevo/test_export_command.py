"""`softevo export` as a user runs it: `main(argv)` in process, real files written and read back,
the format from --format or the suffix, and every failure one line on stderr (exit 1) or a usage
error (exit 2)."""

from __future__ import annotations

import io
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
import trimesh

from softevo.core.outputs.export import FORMATS, export_robot
from softevo.core.robots.robot_file import load_robot
from tests.softevo.inprocess import softevo


def test_help_describes_the_formats() -> None:
    done = softevo("export", "--help")
    assert done.returncode == 0
    assert all(format in done.stdout for format in FORMATS) and "Elastic_Mod" in done.stdout
    assert "export" in softevo("--help").stdout


@pytest.mark.parametrize("format", FORMATS)
def test_export_writes_the_cores_bytes(format: str, examples: Path, tmp_path: Path) -> None:
    source = examples / "crawler_4x4x4.json"
    out = tmp_path / f"crawler.{format}"
    done = softevo("export", str(source), "--out", str(out))  # the format from the suffix
    assert done.returncode == 0, done.stderr
    assert out.read_bytes() == export_robot(load_robot(source), format)
    assert done.stderr.strip() == f"{out}: {format}, {out.stat().st_size} bytes"


def test_format_option_names_a_suffix_that_names_none(examples: Path, tmp_path: Path) -> None:
    out = tmp_path / "robot.bin"
    done = softevo(
        "export", str(examples / "crawler_4x4x4.json"), "--format", "vxa", "--out", str(out)
    )
    assert done.returncode == 0, done.stderr
    root = ET.fromstring(out.read_bytes())
    assert root.tag == "VXA" and len(root.findall("./VXC/Structure/Data/Layer")) == 4
    stl = tmp_path / "robot.stl"
    cube = str(examples / "paper_cube.json")
    done = softevo("export", cube, "--format", "stl", "--out", str(stl))
    assert done.returncode == 0, done.stderr
    mesh = trimesh.load(io.BytesIO(stl.read_bytes()), file_type="stl")
    assert mesh.is_watertight and mesh.volume == pytest.approx(1.0)


def test_a_format_that_contradicts_the_suffix_is_refused(examples: Path, tmp_path: Path) -> None:
    """STL bytes in a .glb file would be the bug `plot` had: refused, nothing written."""
    out = tmp_path / "robot.glb"
    cube = str(examples / "paper_cube.json")
    done = softevo("export", cube, "--format", "stl", "--out", str(out))
    assert done.returncode == 2 and "--format stl but --out" in done.stderr and "glb" in done.stderr
    assert not out.exists()


def test_usage_errors_exit_2(examples: Path, tmp_path: Path) -> None:
    robot = str(examples / "crawler_4x4x4.json")
    no_suffix = softevo("export", robot, "--out", str(tmp_path / "robot.txt"))
    assert no_suffix.returncode == 2 and "--format is needed" in no_suffix.stderr
    assert not (tmp_path / "robot.txt").exists()
    bad = softevo("export", robot, "--format", "obj", "--out", str(tmp_path / "r.obj"))
    assert bad.returncode == 2 and "invalid choice: 'obj'" in bad.stderr
    assert softevo("export", robot).returncode == 2  # --out is required


def test_failures_are_one_line_and_exit_1(examples: Path, tmp_path: Path) -> None:
    cube = softevo("export", str(examples / "paper_cube.json"), "--out", str(tmp_path / "c.vxa"))
    assert cube.returncode == 1 and cube.stderr.count("\n") == 1
    assert cube.stderr.startswith("softevo export: error: ") and "vxa needs" in cube.stderr
    missing = softevo("export", str(tmp_path / "none.json"), "--out", str(tmp_path / "r.stl"))
    assert missing.returncode == 1 and "cannot read" in missing.stderr
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "softevo.robot/1", "shape": [1, 1, 1], "voxels": ["gold"]}')
    invalid = softevo("export", str(bad), "--out", str(tmp_path / "r.stl"))
    assert invalid.returncode == 1 and "voxels.0: unknown label 'gold'" in invalid.stderr
    unwritable = tmp_path / "no" / "such" / "dir.stl"
    done = softevo("export", str(examples / "crawler_4x4x4.json"), "--out", str(unwritable))
    assert done.returncode == 1 and f"{unwritable}: cannot write" in done.stderr
