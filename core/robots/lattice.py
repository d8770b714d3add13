"""Voxel lattices: which masses and springs a grid of filled voxels is made of.

Voxels share their corner masses and the springs on shared edges and faces, so a lattice is
built once per occupancy pattern and springs are deduplicated. Numbering is canonical and part of
the robot-file contract (per-spring parameters are listed in this order):

* lattice points of a (nx, ny, nz) grid are numbered x fastest, then y, then z, over the
  (nx+1)(ny+1)(nz+1) corners; masses are the corners of kept voxels, in that order;
* springs are all pairs of corners of each kept voxel (28 per voxel: 12 edges, 12 face
  diagonals, 4 body diagonals), deduplicated, sorted by (first mass, second mass), first < second.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

#: Corner offsets of one voxel, x fastest: corner n is at (n & 1, (n >> 1) & 1, (n >> 2) & 1).
CORNER_OFFSETS = np.array([(n & 1, (n >> 1) & 1, (n >> 2) & 1) for n in range(8)], dtype=np.int64)
#: The 28 corner pairs of one voxel, in lexicographic order.
CORNER_PAIRS = np.array(list(combinations(range(8), 2)), dtype=np.int64)


class LatticeError(ValueError):
    """The voxel grid describes no robot (for example, every voxel is empty)."""


@dataclass(frozen=True, eq=False)
class Lattice:
    """Masses and springs of the kept voxels of a grid.

    Attributes:
        shape: grid shape (nx, ny, nz).
        kept: bool array [nx*ny*nz], the voxels that were built (largest face-connected group).
        points: int array [M], lattice-point index of each mass.
        rest_positions: float array [M, 3], mass positions in units of the edge length.
        springs: int array [S, 2], mass indices of each spring, first < second.
        spring_lengths: float array [S], rest length in units of the edge length (1, sqrt2, sqrt3).
        spring_voxels: int array [V_kept * 28, 2] of (spring index, voxel index): which kept
            voxels share each spring (an edge is shared by up to 4, a face diagonal by up to 2).
    """

    shape: tuple[int, int, int]
    kept: np.ndarray
    points: np.ndarray
    rest_positions: np.ndarray
    springs: np.ndarray
    spring_lengths: np.ndarray
    spring_voxels: np.ndarray

    @property
    def n_masses(self) -> int:
        return len(self.points)

    @property
    def n_springs(self) -> int:
        return len(self.springs)


def voxel_index(shape: tuple[int, int, int], x: int, y: int, z: int) -> int:
    """Flat index of voxel (x, y, z): x fastest, then y, then z."""
    nx, ny, _ = shape
    return x + nx * (y + ny * z)


def largest_component(filled: np.ndarray, shape: tuple[int, int, int]) -> np.ndarray:
    """Keep the largest face-connected group of filled voxels.

    Ties go to the group holding the lowest voxel index, so the choice is deterministic.
    `filled` is a bool array [nx*ny*nz]; returns a bool array of the same shape.
    """
    nx, ny, nz = shape
    grid = filled.reshape(nz, ny, nx)
    labels = np.full(grid.shape, -1, dtype=np.int64)
    best_label, best_size, n_labels = -1, 0, 0
    for start in np.flatnonzero(filled):
        z0, rem = divmod(int(start), nx * ny)
        y0, x0 = divmod(rem, nx)
        if labels[z0, y0, x0] >= 0:
            continue
        labels[z0, y0, x0] = n_labels
        stack, size = [(z0, y0, x0)], 0
        while stack:
            z, y, x = stack.pop()
            size += 1
            for dz, dy, dx in ((1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)):
                zz, yy, xx = z + dz, y + dy, x + dx
                inside = 0 <= zz < nz and 0 <= yy < ny and 0 <= xx < nx
                if inside and grid[zz, yy, xx] and labels[zz, yy, xx] < 0:
                    labels[zz, yy, xx] = n_labels
                    stack.append((zz, yy, xx))
        if size > best_size:
            best_label, best_size = n_labels, size
        n_labels += 1
    if best_label < 0:
        raise LatticeError("the grid has no filled voxel: there is no robot to build")
    return (labels == best_label).reshape(-1)


def build_lattice(filled: np.ndarray, shape: tuple[int, int, int]) -> Lattice:
    """Build the masses and springs of the largest face-connected group of `filled` voxels."""
    nx, ny, nz = shape
    filled = np.asarray(filled, dtype=bool).reshape(-1)
    if filled.size != nx * ny * nz:
        raise LatticeError(f"expected {nx * ny * nz} voxels for shape {shape}, got {filled.size}")
    kept = largest_component(filled, shape)
    voxels = np.flatnonzero(kept)
    vz, rem = np.divmod(voxels, nx * ny)
    vy, vx = np.divmod(rem, nx)
    origin = np.stack([vx, vy, vz], axis=1)  # [V, 3]
    corners = origin[:, None, :] + CORNER_OFFSETS[None, :, :]  # [V, 8, 3]
    px, py = nx + 1, ny + 1
    corner_points = corners[..., 0] + px * (corners[..., 1] + py * corners[..., 2])  # [V, 8]

    points = np.unique(corner_points)
    corner_mass = np.searchsorted(points, corner_points)  # [V, 8]
    pair_masses = corner_mass[:, CORNER_PAIRS]  # [V, 28, 2]; first < second by construction
    keys = pair_masses[..., 0] * len(points) + pair_masses[..., 1]
    unique_keys, spring_of_pair = np.unique(keys.reshape(-1), return_inverse=True)
    springs = np.stack(np.divmod(unique_keys, len(points)), axis=1)

    pz, rem = np.divmod(points, px * py)
    py_, px_ = np.divmod(rem, px)
    rest_positions = np.stack([px_, py_, pz], axis=1).astype(np.float64)
    delta = rest_positions[springs[:, 1]] - rest_positions[springs[:, 0]]
    spring_lengths = np.sqrt((delta * delta).sum(axis=1))
    spring_voxels = np.stack([spring_of_pair, np.repeat(voxels, 28)], axis=1)
    return Lattice(
        shape=(nx, ny, nz),
        kept=kept,
        points=points,
        rest_positions=rest_positions,
        springs=springs.astype(np.int64),
        spring_lengths=spring_lengths,
        spring_voxels=spring_voxels.astype(np.int64),
    )


def spring_point_keys(lattice: Lattice) -> np.ndarray:
    """One int key per spring, from its two lattice points; sorted, like the springs themselves.

    Keys of the same spring agree between lattices of the same grid shape, so they map the springs
    of any robot onto the springs of the full (all voxels filled) lattice.
    """
    nx, ny, nz = lattice.shape
    n_points = (nx + 1) * (ny + 1) * (nz + 1)
    points = lattice.points[lattice.springs]
    return points[:, 0] * n_points + points[:, 1]


def full_lattice(shape: tuple[int, int, int]) -> Lattice:
    """The lattice of the grid with every voxel filled."""
    return build_lattice(np.ones(shape[0] * shape[1] * shape[2], dtype=bool), shape)
