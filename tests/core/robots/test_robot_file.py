"""Robot files: the stable `softevo.robot/1` format, read back exactly, and every kind of bad file
refused with a message that names the field."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from softevo.core.robots.robot import SpringRobot, VoxelRobot
from softevo.core.robots.robot_file import (
    RobotFileError,
    load_robot,
    parse_robot,
    robot_to_json,
    with_sim,
)


def voxel_file(**changes: object) -> dict:
    document = {
        "format": "softevo.robot/1",
        "shape": [2, 1, 1],
        "voxels": ["hard", "sine"],
        "actuation": {"a": 0.1, "b": 0.5, "c": 1.0},
        "sim": {"duration": 2.0},
    }
    document.update(changes)
    return document


def test_voxel_robot_round_trips_through_json() -> None:
    robot = parse_robot(voxel_file())
    assert isinstance(robot, VoxelRobot)
    assert robot.shape == (2, 1, 1)
    assert robot.voxels == ("hard", "sine")
    assert (robot.actuation.a, robot.actuation.b, robot.actuation.c) == (0.1, 0.5, 1.0)
    assert robot.sim.duration == 2.0 and robot.sim.dt == 0.0005
    document = json.loads(json.dumps(robot_to_json(robot)))
    assert document["format"] == "softevo.robot/1"
    assert document["sim"]["friction"] == 0.6  # the full settings used are written
    again = parse_robot(document)
    assert again.voxels == robot.voxels and again.sim == robot.sim


def test_spring_robot_round_trips_and_defaults_to_filled() -> None:
    springs = [[1000.0, 0.0, 1.0, 0.0]] * 27 + [[5000.0, 0.05, 1.0, 0.5]]
    robot = parse_robot({"format": "softevo.robot/1", "shape": [1, 1, 1], "springs": springs})
    assert isinstance(robot, SpringRobot)
    assert robot.filled == (True,)
    again = parse_robot(robot_to_json(robot))
    np.testing.assert_array_equal(again.springs, np.array(springs))


def test_shipped_examples_load(examples: Path) -> None:
    files = sorted(examples.glob("*.json"))
    assert {f.name for f in files} >= {
        "breathing_cube.json",
        "paper_cube.json",
        "crawler_4x4x4.json",
    }
    for path in files:
        load_robot(path)


@pytest.mark.parametrize(
    ("changes", "field", "words"),
    [
        ({"colour": "red"}, "colour", "Extra inputs"),
        ({"format": "softevo.robot/2"}, "format", "softevo.robot/1"),
        ({"shape": [2, 1]}, "shape", "at least 3"),
        ({"shape": [2, 1, "1"]}, "shape.2", "integer"),
        ({"shape": [0, 1, 1]}, "shape.0", "greater than or equal to 1"),
        ({"shape": [32, 32, 32]}, "shape", "more than the limit"),
        ({"voxels": ["hard"]}, "voxels", "expected 2 labels"),
        ({"voxels": ["hard", "jelly"]}, "voxels.1", "unknown label 'jelly'"),
        ({"voxels": ["empty", "empty"]}, "voxels", "no filled voxel"),
        ({"actuation": {"a": 2.0}}, "actuation.a", "less than or equal to 1"),
        ({"actuation": {"b": "big"}}, "actuation.b", "valid number"),
        ({"actuation": {"d": 1.0}}, "actuation.d", "Extra inputs"),
        ({"sim": {"dt": 0}}, "sim.dt", "greater than 0"),
        ({"sim": {"dt": -0.001}}, "sim.dt", "greater than 0"),
        ({"sim": {"duration": 0}}, "sim.duration", "greater than 0"),
        ({"sim": {"friction": math.nan}}, "sim.friction", "finite"),
        ({"sim": {"gravity": math.inf}}, "sim.gravity", "finite"),
        ({"sim": {"dt": "0.001"}}, "sim.dt", "valid number"),
        ({"sim": {"wind": 3}}, "sim.wind", "Extra inputs"),
        ({"sim": {"settle_time": 5.0, "duration": 2.0}}, "sim.settle_time", "shorter than"),
    ],
)
def test_bad_voxel_files_are_refused_naming_the_field(
    changes: dict, field: str, words: str
) -> None:
    with pytest.raises(RobotFileError) as caught:
        parse_robot(voxel_file(**changes))
    message = str(caught.value)
    assert message.startswith(f"{field}:") or f"{field}:" in message, message
    assert words in message, message
    assert "\n" not in message


def test_missing_voxels_and_springs_is_refused() -> None:
    document = voxel_file()
    del document["voxels"]
    with pytest.raises(RobotFileError, match=r"^voxels: required"):
        parse_robot(document)


@pytest.mark.parametrize(
    ("springs", "field", "words"),
    [
        ([[1000.0, 0.0, 1.0, 0.0]] * 27, "springs", "expected 28 entries"),
        ([[1000.0, 0.0, 1.0]] * 28, "springs.0", "at least 4"),
        ([[-1.0, 0.0, 1.0, 0.0]] * 28, "springs.0", "greater than or equal to 0"),
        ([[1000.0, 0.05, 1.0, 0.0]] * 27 + [[1000.0, 0.05, 2.0, 0.0]], "springs", "one frequency"),
    ],
)
def test_bad_spring_files_are_refused(springs: list, field: str, words: str) -> None:
    document = {"format": "softevo.robot/1", "shape": [1, 1, 1], "springs": springs}
    with pytest.raises(RobotFileError) as caught:
        parse_robot(document)
    assert str(caught.value).startswith(f"{field}"), caught.value
    assert words in str(caught.value), caught.value


def test_spring_robot_refuses_material_labels_and_actuation() -> None:
    springs = [[1000.0, 0.0, 1.0, 0.0]] * 28
    base = {"format": "softevo.robot/1", "shape": [1, 1, 1], "springs": springs}
    with pytest.raises(RobotFileError, match=r"voxels\.0: unknown label 'hard'"):
        parse_robot({**base, "voxels": ["hard"]})
    with pytest.raises(RobotFileError, match=r"^actuation: not allowed"):
        parse_robot({**base, "actuation": {"a": 0.0}})


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("{not json", "not valid JSON"),
        ('{"format": "softevo.robot/1", "shape": [1, 1, 1], "voxels": [NaN]}', "NaN"),
        ("[" * 100_000 + "]" * 100_000, "nested too deeply"),
        ("[1, 2, 3]", "expected a JSON object"),
    ],
)
def test_malformed_files_are_refused(tmp_path: Path, text: str, words: str) -> None:
    path = tmp_path / "robot.json"
    path.write_text(text)
    with pytest.raises(RobotFileError, match=words):
        load_robot(path)


def test_missing_file_is_refused(tmp_path: Path) -> None:
    with pytest.raises(RobotFileError, match="cannot read"):
        load_robot(tmp_path / "absent.json")


def test_with_sim_validates_overrides() -> None:
    robot = parse_robot(voxel_file())
    assert with_sim(robot, duration=3.0).sim.duration == 3.0
    with pytest.raises(RobotFileError, match=r"^sim\.duration"):
        with_sim(robot, duration=-1.0)
