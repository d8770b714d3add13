"""A replay: one robot simulated once more with its frames recorded, for a 3D viewer. Computed
here for the API's local path and for the RQ workers' replay job alike.

The frame rate is lowered until the frames hold at most `max_positions` mass positions (a
512-voxel robot over 60 s would otherwise be hundreds of megabytes of JSON)."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from softevo.core.limits import MAX_REPLAY_POSITIONS
from softevo.core.nulls import to_null
from softevo.core.outputs.export import mass_faces
from softevo.core.robots.lattice import Lattice
from softevo.core.robots.robot import Robot, build_mechanics
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.robots.terrain import mesh

if TYPE_CHECKING:  # the physics loads only when a replay is asked
    from softevo.core.physics.simulate import Trajectory


def record_every(robot: Robot, masses: int, fps: float, max_positions: int) -> int:
    """Steps between frames: `fps` frames per simulated second, fewer if the frames would hold
    more than `max_positions` positions."""
    sim = robot.sim
    wanted = max(1, round(1.0 / (fps * sim.step)))
    frames_allowed = max(2, max_positions // max(1, masses) - 1)
    return max(wanted, math.ceil(sim.n_steps / frames_allowed))


def replay_json(robot_file: dict[str, Any], fps: float, max_positions: int) -> bytes:
    """`replay_frames` of a robot file, as JSON bytes: what a separate process returns, so the
    process that serves it never turns a million positions into objects."""
    import json

    from softevo.core.robots.robot_file import parse_robot

    data = replay_frames(parse_robot(robot_file), fps, max_positions)
    return json.dumps(data, separators=(",", ":"), allow_nan=False).encode()


def replay_frames(
    robot: Robot, fps: float, max_positions: int = MAX_REPLAY_POSITIONS
) -> dict[str, Any]:
    """The robot's speed and other measures, the frame rate used, the robot file, the terrain
    under its path and its trajectory (JSON)."""
    from softevo.core.physics import simulate  # the physics loads only when a replay is asked

    mechanics = build_mechanics(robot)
    every = record_every(robot, mechanics.n_masses, fps, max_positions)
    result, trajectory = simulate(mechanics, record_every=every)
    assert trajectory is not None
    measures = result.to_json()
    trajectory, blew_up_at = finite_part(trajectory)
    return {
        "speed": to_null(result.speed),
        "measures": {key: measures[key] for key in MEASURES},
        "fps": 1.0 / (every * robot.sim.step),
        "blew_up_at": blew_up_at,
        "robot": robot_to_json(robot),
        "terrain": terrain_view(robot.sim.terrain, trajectory.frames),
        **voxel_faces(robot, mechanics.lattice),
        **trajectory.to_json(),
    }


def finite_part(trajectory: Trajectory) -> tuple[Trajectory, float | None]:
    """The frames up to the first with a position that is not finite, and that frame's time
    (s): a robot whose simulation blew up (too large a `sim.dt`) is replayed until it does,
    and says when, instead of failing on NaN. (None, with every frame: it never blew up.)"""
    finite = np.isfinite(trajectory.frames).all(axis=(1, 2))
    if finite.all():
        return trajectory, None
    first = max(1, int(np.argmin(finite)))  # the first frame is the robot at rest, never NaN
    kept = replace(trajectory, times=trajectory.times[:first], frames=trajectory.frames[:first])
    return kept, float(trajectory.times[first])


def voxel_faces(robot: Robot, lattice: Lattice) -> dict[str, Any]:
    """The robot's outer voxel faces as quads of mass indices, wound outward
    (`softevo.core.outputs.export.mass_faces`), each face's voxel and material ("filled" for robots
    whose springs carry their own): a viewer moves each quad's corners with its masses."""
    faces, voxels, labels = mass_faces(robot, lattice)
    return {
        "faces": faces.tolist(),
        "face_voxels": voxels.tolist(),
        "face_materials": labels.tolist(),
    }


#: What a replay reports of its simulation besides speed.
MEASURES = ("forward_speed", "climb_rate", "energy", "cost_of_transport")


def terrain_view(terrain: Any, frames: Any) -> dict[str, Any]:
    """The terrain under the robot's path, MARGIN metres around it, for the viewer to draw."""
    low = np.maximum(frames.min(axis=(0, 1)), -FARTHEST)  # a robot flung away is not followed
    high = np.minimum(frames.max(axis=(0, 1)), FARTHEST)
    x_range = (math.floor(low[0]) - MARGIN, math.ceil(high[0]) + MARGIN)
    y_range = (math.floor(low[1]) - MARGIN, math.ceil(high[1]) + MARGIN)
    view: dict[str, Any] = terrain.model_dump()
    if terrain.kind != "flat":
        view["mesh"] = mesh(terrain, x_range, y_range, MESH_STEP)
    return view


#: Metres of terrain drawn around the robot's path, the grid's spacing (m) where the mesh's cap
#: (`softevo.core.robots.terrain.MAX_MESH_POINTS`) allows it, and the farthest from the origin
#: drawn (m).
MARGIN, MESH_STEP, FARTHEST = 4, 0.1, 1e5
