"""What a picture draws (core/outputs/picture.py): a co-designed robot's actuated voxels in the hue
of their phase rather than their material's colour, and the terrain under the robot."""

from __future__ import annotations

import io

import numpy as np
from PIL import Image

from softevo.core.outputs import picture
from softevo.core.robots.robot import VoxelRobot
from softevo.core.robots.settings import SimSettings
from softevo.core.robots.terrain import Steps


def pixels(robot: VoxelRobot) -> np.ndarray:
    with Image.open(io.BytesIO(picture.thumbnail_png(robot))) as image:
        return np.asarray(image.convert("RGB"), dtype=np.int16)


def test_phases_colour_the_actuated_voxels() -> None:
    plain = VoxelRobot(shape=(2, 1, 1), voxels=("sine", "sine"))
    phased = VoxelRobot(
        shape=(2, 1, 1), voxels=("sine", "sine"), phases=(0.0, 2.0), amplitudes=(1.0, 1.0)
    )
    assert np.abs(pixels(plain) - pixels(phased)).sum() > 0
    scene = picture._Scene(phased)
    assert len(np.unique(scene.colours.round(3), axis=0)) == 2  # two phases, two hues
    assert len(np.unique(picture._Scene(plain).colours.round(3), axis=0)) == 1


def test_the_terrain_is_drawn() -> None:
    flat = VoxelRobot(shape=(1, 1, 1), voxels=("hard",))
    sim = SimSettings(terrain=Steps(height=0.5, depth=1.5))
    stairs = VoxelRobot(shape=(1, 1, 1), voxels=("hard",), sim=sim)
    on_flat = picture._Scene(flat).mechanics.positions
    on_stairs = picture._Scene(stairs).mechanics.positions  # moved along x to face the riser
    assert np.allclose(on_flat - on_flat.min(axis=0), on_stairs - on_stairs.min(axis=0))
    assert np.abs(pixels(flat) - pixels(stairs)).sum() > 0
