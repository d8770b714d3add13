"""Steps and hurdles are placed relative to the robot's front face (the largest x of its masses
at rest): the first riser or bar stands FIRST_FEATURE_GAP ahead of it whatever the box, so a
small robot meets it as a 4x4x4 one does (issue 39: they stood at x = 4.15 m whatever the box,
and 3x3x3 robots gave the same curves on stairs, hurdles and flat ground)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from softevo.core.physics import simulate
from softevo.core.robots.robot import build_mechanics
from softevo.core.robots.robot_file import parse_robot
from softevo.core.robots.terrain import FIRST_FEATURE_GAP


def _crawler(examples: Path, terrain: dict, front: int) -> dict:
    """The example crawler turned to crawl along +x (its voxels mirrored in x), with no voxel
    at or ahead of x = `front` (its box stays 4x4x4: the robot is shorter than its box)."""
    document = json.loads((examples / "crawler_4x4x4.json").read_text())
    voxels = np.flip(np.array(document["voxels"]).reshape(4, 4, 4), 2)  # [z][y][x]
    voxels[:, :, front:] = "empty"
    document["voxels"] = voxels.ravel().tolist()
    document["sim"] = {**document["sim"], "terrain": terrain}
    return document


@pytest.mark.parametrize(
    ("terrain", "first"),
    [
        ({"kind": "steps", "height": 0.2, "depth": 4.15}, 4.15),
        ({"kind": "hurdles", "height": 0.15, "spacing": 2.5, "width": 0.5}, 2.5),
    ],
)
@pytest.mark.parametrize("front", [4, 3, 2])
def test_the_first_feature_stands_just_ahead_of_the_front_face(
    examples: Path, terrain: dict, first: float, front: int
) -> None:
    robot = parse_robot(_crawler(examples, terrain, front))
    positions = build_mechanics(robot).positions
    assert positions[:, 0].max() == pytest.approx(first - FIRST_FEATURE_GAP)
    assert positions[:, 0].max() - positions[:, 0].min() == pytest.approx(front)


def test_a_4x4x4_robot_filling_its_front_layer_is_where_it_was(examples: Path) -> None:
    """On the task presets' terrain the shift is exactly 0: their 4x4x4 results stand."""
    robot = parse_robot(_crawler(examples, {"kind": "steps"}, 4))
    assert build_mechanics(robot).positions[:, 0].max() == 4.0


@pytest.mark.parametrize("kind", ["steps", "hurdles"])
def test_a_robot_shorter_than_its_box_meets_the_feature(examples: Path, kind: str) -> None:
    flat = simulate(parse_robot(_crawler(examples, {"kind": "flat"}, 3)))[0]
    featured = simulate(parse_robot(_crawler(examples, {"kind": kind}, 3)))[0]
    assert flat.forward_speed > 0.02  # it crawls forward about 0.4 m in the measured 9 s
    assert featured.forward_speed < 0.5 * flat.forward_speed  # and the feature slows it
