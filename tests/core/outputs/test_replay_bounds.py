"""A replay stays bounded whatever its terrain and its robot: the terrain mesh holds at most
MAX_MESH_POINTS heights (a tread of a nanometre, a long slide on rough ground), and a robot
whose simulation blew up is replayed until it did, never a NaN that fails the encoding."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from softevo.core.outputs.replay import replay_frames, terrain_view
from softevo.core.robots.robot import Actuation, VoxelRobot
from softevo.core.robots.settings import SimSettings
from softevo.core.robots.terrain import MAX_MESH_POINTS, Hurdles, Rough, Steps, mesh


def heights(view: dict) -> int:
    return len(view["x"]) * len(view["y"])


@pytest.mark.parametrize(
    "terrain",
    [
        Steps.model_construct(height=0.01, depth=1e-4),
        Steps.model_construct(height=0.01, depth=1e-9),
        Hurdles.model_construct(height=0.1, spacing=1e-4, width=1e-5),
        Hurdles.model_construct(height=0.1, spacing=1e-9, width=1e-10),
    ],
)  # below MIN_TERRAIN_LENGTH, which a config refuses: the mesh is bounded anyway
def test_a_terrain_of_tiny_features_gives_a_bounded_mesh(terrain: Steps | Hurdles) -> None:
    started = time.perf_counter()
    drawn = mesh(terrain, (-4.0, 36.0), (-4.0, 5.0), 0.1)
    assert heights(drawn) <= MAX_MESH_POINTS and len(drawn["z"][0]) == len(drawn["x"])
    assert time.perf_counter() - started < 2


def test_a_long_slide_on_rough_ground_gives_a_bounded_mesh() -> None:
    frames = np.array([[[0.0, 0.0, 0.0]], [[120.0, -90.0, 0.5]]])  # [F, M, 3]
    view = terrain_view(Rough(amplitude=0.1, wavelength=2.0), frames)
    assert heights(view["mesh"]) <= MAX_MESH_POINTS
    assert view["mesh"]["x"][0] <= -4 and view["mesh"]["x"][-1] >= 124  # the whole path drawn
    assert len(view["mesh"]["z"]) == len(view["mesh"]["y"])


def test_a_mesh_under_the_cap_keeps_its_grid_and_upright_faces() -> None:
    drawn = mesh(Steps(height=0.2, depth=1.0), (-4.0, 6.0), (-1.0, 1.0), 0.1)
    assert len(drawn["x"]) == 101 + 6 and drawn["y"] == [-1.0, 1.0]  # the grid and 6 risers
    assert {0.999999, 1.0, 5.999999, 6.0} <= set(drawn["x"])
    assert drawn["z"][0][drawn["x"].index(1.0)] == 0.2


def test_a_robot_that_blew_up_replays_until_it_did() -> None:
    """sim.dt 0.003 is accepted and makes this robot blow up: a replay says when, with the
    finite frames before, not a 500 from a NaN turned into an integer."""
    sim = SimSettings(dt=0.003, duration=2.0)
    robot = VoxelRobot((2, 2, 2), ("sine",) * 8, Actuation(1.0, 0.5, 0.0), sim)
    data = replay_frames(robot, 10.0)
    assert data["speed"] is None and data["blew_up_at"] is not None
    assert 0 < data["blew_up_at"] <= 2.0 and data["times"][-1] < data["blew_up_at"]
    assert np.isfinite(np.array(data["frames"])).all()
    json.dumps(data, allow_nan=False)
    steady = replay_frames(
        VoxelRobot((2, 2, 2), ("sine",) * 8, Actuation(1.0, 0.5, 0.0), SimSettings(duration=2.0)),
        10.0,
    )
    assert steady["blew_up_at"] is None and steady["times"][-1] == pytest.approx(2.0)
