"""Voxel lattices: mass and spring counts, canonical numbering, and which voxels are built."""

from __future__ import annotations

import math

import numpy as np
import pytest

from softevo.core.robots.lattice import LatticeError, build_lattice, full_lattice, voxel_index


def lattice_of(shape: tuple[int, int, int], filled_voxels: list[tuple[int, int, int]]):
    filled = np.zeros(shape[0] * shape[1] * shape[2], dtype=bool)
    for x, y, z in filled_voxels:
        filled[voxel_index(shape, x, y, z)] = True
    return build_lattice(filled, shape)


@pytest.mark.parametrize(
    ("shape", "masses", "springs"),
    [
        ((1, 1, 1), 8, 28),
        ((2, 1, 1), 12, 50),  # 56 - 6 springs of the shared face (4 edges, 2 diagonals)
        ((2, 2, 1), 18, 89),  # 4 * 28 - 4 shared faces * 6 + the central edge counted back
        ((4, 4, 4), 125, 1036),
    ],
)
def test_solid_block_counts(shape, masses, springs) -> None:
    lattice = full_lattice(shape)
    assert lattice.n_masses == masses
    assert lattice.n_springs == springs


def test_solid_block_counts_follow_the_formula() -> None:
    """Springs of a solid a x b x c block: edges + face diagonals + body diagonals."""
    for a, b, c in [(3, 2, 1), (3, 3, 3), (5, 2, 4)]:
        edges = a * (b + 1) * (c + 1) + (a + 1) * b * (c + 1) + (a + 1) * (b + 1) * c
        faces = 2 * (a * b * (c + 1) + a * (b + 1) * c + (a + 1) * b * c)
        body = 4 * a * b * c
        lattice = full_lattice((a, b, c))
        assert lattice.n_masses == (a + 1) * (b + 1) * (c + 1)
        assert lattice.n_springs == edges + faces + body


def test_cube_springs_are_12_edges_12_face_diagonals_4_body_diagonals() -> None:
    lattice = full_lattice((1, 1, 1))
    lengths = np.round(lattice.spring_lengths**2).astype(int)
    assert np.bincount(lengths).tolist() == [0, 12, 12, 4]
    delta = (
        lattice.rest_positions[lattice.springs[:, 1]]
        - lattice.rest_positions[lattice.springs[:, 0]]
    )
    np.testing.assert_allclose(np.linalg.norm(delta, axis=1), lattice.spring_lengths)


def test_numbering_is_canonical() -> None:
    lattice = full_lattice((3, 2, 2))
    springs = lattice.springs
    assert (springs[:, 0] < springs[:, 1]).all()
    keys = springs[:, 0] * lattice.n_masses + springs[:, 1]
    assert (np.diff(keys) > 0).all()  # sorted, no duplicates
    # Points x fastest, then y, then z.
    x, y, z = lattice.rest_positions.T
    assert np.array_equal(lattice.points, x + 4 * (y + 3 * z))
    assert np.array_equal(lattice.rest_positions[1], [1, 0, 0])
    assert np.array_equal(lattice.rest_positions[4], [0, 1, 0])
    assert np.array_equal(lattice.rest_positions[12], [0, 0, 1])
    assert set(np.round(lattice.spring_lengths, 12)) == {
        1.0,
        round(math.sqrt(2), 12),
        round(math.sqrt(3), 12),
    }


def test_shared_face_springs_list_both_voxels() -> None:
    lattice = full_lattice((2, 1, 1))
    owners = np.bincount(lattice.spring_voxels[:, 0], minlength=lattice.n_springs)
    assert np.bincount(owners).tolist() == [0, 44, 6]  # 6 springs on the shared face
    shared = np.flatnonzero(owners == 2)
    x = lattice.rest_positions[lattice.springs[shared]][..., 0]
    assert (x == 1).all()  # both ends on the face x = 1


def test_only_the_largest_face_connected_group_is_built() -> None:
    shape = (5, 1, 1)
    lattice = lattice_of(shape, [(0, 0, 0), (2, 0, 0), (3, 0, 0), (4, 0, 0)])
    assert lattice.kept.tolist() == [False, False, True, True, True]
    assert lattice.n_masses == 16 and lattice.n_springs == 28 * 3 - 6 * 2
    assert lattice.rest_positions[:, 0].min() == 2  # the lone voxel at x = 0 is gone


@pytest.mark.parametrize(
    ("shape", "voxels", "why"),
    [
        ((2, 2, 1), [(0, 0, 0), (1, 1, 0)], "edge"),
        ((2, 2, 2), [(0, 0, 0), (1, 1, 1)], "corner"),
        ((3, 1, 1), [(0, 0, 0), (2, 0, 0)], "apart"),
    ],
)
def test_voxels_touching_at_an_edge_or_corner_are_not_connected(shape, voxels, why) -> None:
    lattice = lattice_of(shape, voxels)
    assert lattice.kept.sum() == 1, why
    assert lattice.kept[0]  # a tie goes to the group holding the lowest voxel index
    assert lattice.n_masses == 8 and lattice.n_springs == 28


def test_tie_goes_to_the_lowest_voxel_index() -> None:
    shape = (5, 1, 1)
    lattice = lattice_of(shape, [(3, 0, 0), (4, 0, 0), (0, 0, 0), (1, 0, 0)])
    assert lattice.kept.tolist() == [True, True, False, False, False]


def test_l_shape_is_one_group() -> None:
    shape = (2, 2, 2)
    lattice = lattice_of(shape, [(0, 0, 0), (1, 0, 0), (1, 1, 0), (1, 1, 1)])
    assert lattice.kept.sum() == 4


def test_empty_grid_is_refused() -> None:
    with pytest.raises(LatticeError, match="no filled voxel"):
        build_lattice(np.zeros(8, dtype=bool), (2, 2, 2))


def test_wrong_voxel_count_is_refused() -> None:
    with pytest.raises(LatticeError, match="expected 8 voxels"):
        build_lattice(np.ones(7, dtype=bool), (2, 2, 2))
