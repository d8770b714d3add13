"""The replay's voxel faces: every outer face of the simulated body once, as masses, outward."""

from __future__ import annotations

import numpy as np

from softevo.core.outputs.replay import voxel_faces
from softevo.core.robots.robot import Actuation, VoxelRobot, build_mechanics
from softevo.core.robots.settings import SimSettings


def test_faces_are_the_outer_faces_of_the_body_wound_outward() -> None:
    rng = np.random.default_rng(4)
    labels = tuple(rng.choice(["empty", "soft", "hard", "sine", "neg_sine"], 27).tolist())
    robot = VoxelRobot((3, 3, 3), labels, Actuation(0.1, 0.5, 0.0), SimSettings())
    lattice = build_mechanics(robot).lattice
    data = voxel_faces(robot, lattice)
    quads, voxels = np.array(data["faces"]), np.array(data["face_voxels"])
    rest = lattice.rest_positions[quads]  # [F, 4, 3] lattice coordinates
    normal = np.cross(rest[:, 1] - rest[:, 0], rest[:, 2] - rest[:, 0])
    outside = np.floor(rest.mean(axis=1) + 0.5 * normal).astype(int)  # the cell beyond the face
    inside = np.floor(rest.mean(axis=1) - 0.5 * normal).astype(int)
    kept = lattice.kept.reshape(3, 3, 3)  # [z, y, x]

    def filled(cell: np.ndarray) -> bool:
        x, y, z = cell
        return bool(0 <= x < 3 and 0 <= y < 3 and 0 <= z < 3 and kept[z, y, x])

    assert all(filled(c) for c in inside) and not any(filled(c) for c in outside)
    assert [labels[v] for v in voxels] == data["face_materials"]
    cells = [(int(v), tuple(n)) for v, n in zip(voxels, normal.astype(int), strict=True)]
    assert len(set(cells)) == len(cells)  # no face twice
    exposed = sum(
        not filled(np.array([x, y, z]) + d)
        for z, y, x in np.argwhere(kept)
        for d in np.vstack([np.eye(3, dtype=int), -np.eye(3, dtype=int)])
    )
    assert len(cells) == exposed  # and every outer face
