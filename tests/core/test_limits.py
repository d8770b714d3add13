"""One ceiling for every layer (core/limits.py): a run config, a robot file and the service's
settings accept and refuse the same sizes."""

from __future__ import annotations

import pytest

from softevo.api.settings import Settings
from softevo.core.config import ConfigError, resolve
from softevo.core.limits import MAX_SIDE, MAX_VOXELS
from softevo.core.robots.robot_file import RobotFileError, parse_robot


def robot(shape: list[int]) -> dict:
    voxels = shape[0] * shape[1] * shape[2]
    return {"format": "softevo.robot/1", "shape": shape, "voxels": ["hard"] * voxels}


def test_a_run_and_a_robot_file_share_the_largest_side() -> None:
    widest = [MAX_SIDE, 2, 1]
    assert resolve({"preset": "quick", "shape": widest}).shape == tuple(widest)
    assert parse_robot(robot(widest)).shape == tuple(widest)
    with pytest.raises(ConfigError, match=f"between 1 and {MAX_SIDE}"):
        resolve({"preset": "quick", "shape": [MAX_SIDE + 1, 1, 1]})
    with pytest.raises(RobotFileError, match="shape"):
        parse_robot(robot([MAX_SIDE + 1, 1, 1]))


def test_the_service_cannot_be_set_past_the_ceiling() -> None:
    assert (
        Settings.from_env({"SOFTEVO_MAX_VOXELS": str(MAX_VOXELS)}).limits.max_voxels == MAX_VOXELS
    )
    with pytest.raises(ValueError, match="SOFTEVO_MAX_VOXELS"):
        Settings.from_env({"SOFTEVO_MAX_VOXELS": str(MAX_VOXELS + 1)})
