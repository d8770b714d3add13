"""Robots that leave softevo: a robot as a Voxelyze / VoxCAD / voxcraft-sim `.vxa`, or its voxel
surface as a glTF 2.0 binary (`.glb`, coloured by material) or an STL mesh (docs/export.md).

What is exported is the robot as softevo simulates it: the largest face-connected group of
filled voxels (`Lattice.kept`); voxels that the lattice drops are left out (empty) everywhere.
Meshes are in metres, each voxel an `edge_length` cube at its grid place (voxel (i, j, k) spans
[i, i+1] x [j, j+1] x [k, k+1] edge lengths); only faces between a filled voxel and an empty
cell or the outside are written, so interior walls never reach a slicer or a viewer.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from softevo.core.outputs.vxa import VxaError, to_vxa
from softevo.core.robots.lattice import Lattice, LatticeError, build_lattice
from softevo.core.robots.robot import COLOURS, LABELS, Robot, VoxelRobot

FORMATS = ("vxa", "glb", "stl")
MEDIA_TYPES = {"vxa": "application/xml", "glb": "model/gltf-binary", "stl": "model/stl"}
#: glTF is +Y up, softevo +Z up: (x, y, z) -> (x, z, -y), a rotation (no mirror).
Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


class ExportError(ValueError):
    """A robot that cannot be written in the asked format; the message is one line."""


def format_from_path(path: str | Path) -> str | None:
    """The format a file name asks for by its suffix (`robot.glb` -> glb), None if none."""
    suffix = Path(path).suffix.lower().lstrip(".")
    return suffix if suffix in FORMATS else None


def voxel_grid(robot: Robot) -> np.ndarray:
    """Material labels of the simulated voxels as an (nx, ny, nz) array indexed [x, y, z];
    "empty" where no voxel is built, "filled" for robots whose springs carry the materials."""
    nx, ny, nz = robot.shape
    if isinstance(robot, VoxelRobot):
        labels = np.array(robot.voxels, dtype=object)
        filled = labels != "empty"
    else:
        filled = np.array(robot.filled, dtype=bool)
        labels = np.where(filled, "filled", "empty").astype(object)
    try:
        kept = build_lattice(filled, robot.shape).kept
    except LatticeError as error:
        raise ExportError(str(error)) from None
    labels = np.where(kept, labels, "empty")
    return labels.reshape(nz, ny, nx).transpose(2, 1, 0)  # x fastest in the file order


#: For a face normal to axis a, the two in-plane axes (u, v) with e_u x e_v = e_a.
_IN_PLANE = {0: (1, 2), 1: (2, 0), 2: (0, 1)}
_QUAD = np.array([(0, 0), (1, 0), (1, 1), (0, 1)])  # counter-clockwise seen from +e_a


def surface_faces(filled: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The boundary quads of a boolean voxel grid [x, y, z]: integer corner coordinates
    [F, 4, 3] wound counter-clockwise seen from outside (outward normals), and the voxel
    index [F, 3] each quad belongs to."""
    padded = np.pad(filled, 1)
    corners, owners = [], []
    for axis in range(3):
        u, v = _IN_PLANE[axis]
        for sign in (1, -1):
            neighbour = np.roll(padded, -sign, axis=axis)  # neighbour[c] = padded[c + sign*e_a]
            cells = np.argwhere(padded & ~neighbour) - 1  # back to unpadded voxel indices
            quad = _QUAD if sign > 0 else _QUAD[::-1]
            offsets = np.zeros((4, 3), dtype=np.int64)
            offsets[:, axis] = 1 if sign > 0 else 0
            offsets[:, u], offsets[:, v] = quad[:, 0], quad[:, 1]
            corners.append(cells[:, None, :] + offsets[None, :, :])
            owners.append(cells)
    return np.concatenate(corners), np.concatenate(owners)


def mass_faces(robot: Robot, lattice: Lattice) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The simulated body's outer faces as the masses at their corners, for drawings that
    deform with the simulation (the replay, the movies): mass indices [F, 4] wound outward,
    each face's voxel (flat index, x fastest) [F] and material label [F]."""
    grid = voxel_grid(robot)
    quads, owners = surface_faces(grid != "empty")
    nx, ny, _ = robot.shape
    points = quads[..., 0] + (nx + 1) * (quads[..., 1] + (ny + 1) * quads[..., 2])
    voxels = owners[:, 0] + nx * (owners[:, 1] + ny * owners[:, 2])
    labels = grid[owners[:, 0], owners[:, 1], owners[:, 2]].astype(str)
    return np.searchsorted(lattice.points, points), voxels, labels


def _triangles(quads: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quads [F, 4, 3] (integer corners) as shared vertices [V, 3] and triangles [2F, 3]."""
    keys, inverse = np.unique(quads.reshape(-1, 3), axis=0, return_inverse=True)
    index = inverse.reshape(-1, 4)
    faces = np.concatenate([index[:, [0, 1, 2]], index[:, [0, 2, 3]]])
    return keys.astype(np.float64), faces


def surface_meshes(robot: Robot) -> dict[str, Any]:
    """One trimesh.Trimesh per material of the robot's voxel surface (metres, +Z up)."""
    import trimesh  # here, not at import: only the mesh formats need it

    grid = voxel_grid(robot)
    quads, owners = surface_faces(grid != "empty")
    owner_labels = grid[owners[:, 0], owners[:, 1], owners[:, 2]]
    meshes = {}
    for label in (*LABELS[1:], "filled"):
        mine = quads[owner_labels == label]
        if len(mine):
            vertices, faces = _triangles(mine)
            meshes[label] = trimesh.Trimesh(vertices * robot.sim.edge_length, faces, process=False)
    return meshes


def to_stl(robot: Robot) -> bytes:
    """The robot's voxel surface as one binary STL (metres, +Z up), vertices shared."""
    import trimesh

    grid = voxel_grid(robot)
    vertices, faces = _triangles(surface_faces(grid != "empty")[0])
    mesh = trimesh.Trimesh(vertices * robot.sim.edge_length, faces, process=False)
    data = mesh.export(file_type="stl")
    assert isinstance(data, bytes), "trimesh writes binary STL"
    return data


def linear_rgb(colour: tuple[int, int, int]) -> list[float]:
    """An sRGB colour (0..255) as glTF's linear baseColorFactor (0..1), so a viewer shows it
    as the dashboard does."""
    channels = np.asarray(colour, dtype=np.float64) / 255
    linear = np.where(channels <= 0.04045, channels / 12.92, ((channels + 0.055) / 1.055) ** 2.4)
    return [float(c) for c in linear]


def to_glb(robot: Robot) -> bytes:
    """The voxel surface as glTF 2.0 binary: one mesh (and PBR material) per voxel material,
    named by the label, in metres with glTF's +Y up."""
    import trimesh
    from trimesh.visual.material import PBRMaterial
    from trimesh.visual.texture import TextureVisuals

    scene = trimesh.Scene()
    for label, mesh in surface_meshes(robot).items():
        material = PBRMaterial(
            name=label,
            baseColorFactor=[*linear_rgb(COLOURS[label]), 1.0],
            metallicFactor=0.0,
            roughnessFactor=0.8,
        )
        mesh.vertices = mesh.vertices @ Z_UP_TO_Y_UP.T
        mesh.visual = TextureVisuals(material=material)
        scene.add_geometry(mesh, node_name=label, geom_name=label)
    return bytes(scene.export(file_type="glb"))


def export_robot(robot: Robot, format: str) -> bytes:
    """The robot written in `format` (one of FORMATS), as the bytes of the file."""
    if format == "vxa":
        grid = voxel_grid(robot)
        try:
            return to_vxa(robot, grid)
        except VxaError as error:  # the writer's refusal, said as every format's is
            raise ExportError(str(error)) from None
    if format == "glb":
        return to_glb(robot)
    if format == "stl":
        return to_stl(robot)
    raise ExportError(f"unknown format {format!r} (formats: {', '.join(FORMATS)})")


__all__ = [
    "FORMATS",
    "MEDIA_TYPES",
    "ExportError",
    "export_robot",
    "format_from_path",
    "surface_faces",
    "surface_meshes",
    "voxel_grid",
]
