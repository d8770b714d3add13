"""softevo.core.search.pareto against pymoo (a test dependency only) and against hand-made fronts.

pymoo minimises, softevo maximises: pymoo is given the negated values (and reference point).
The point sets hold ties, copies of rows and extremes of very different scales (fixed seeds).
"""

from __future__ import annotations

import numpy as np
import pytest
from pymoo.indicators.hv import HV
from pymoo.operators.survival.rank_and_crowding.metrics import get_crowding_function
from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting

from softevo.core.search import pareto

SEEDS = range(20)


def points(seed: int) -> np.ndarray:
    """[N, M] objective values with ties, duplicate rows and extremes, M in 2..4."""
    rng = np.random.default_rng(seed)
    n, m = int(rng.integers(3, 60)), 2 + seed % 3
    if seed % 4 == 0:  # a coarse grid: ties in every objective
        values = rng.integers(0, 4, size=(n, m)).astype(float)
    else:  # objectives on scales from 1e-6 to 1e9
        values = rng.normal(size=(n, m)) * 10.0 ** rng.integers(-6, 10, size=m)
    copies = rng.integers(0, n, size=n // 4)
    values[copies] = values[rng.integers(0, n)]  # a quarter of the rows are one row's copies
    extreme = rng.integers(0, n)
    values[extreme] = values.min(axis=0)
    values[extreme, seed % m] = 1e12  # the best in one objective, the worst in the others
    return values


def pymoo_ranks(values: np.ndarray) -> np.ndarray:
    return NonDominatedSorting().do(-values, return_rank=True)[1]


@pytest.mark.parametrize("seed", SEEDS)
def test_ranks_equal_pymoo(seed: int) -> None:
    values = points(seed)
    ranks = pareto.nondominated_ranks(values)
    np.testing.assert_array_equal(ranks, pymoo_ranks(values))
    np.testing.assert_array_equal(pareto.nondominated_mask(values), ranks == 0)


@pytest.mark.parametrize("seed", SEEDS)
def test_crowding_equals_pymoo_times_the_number_of_objectives(seed: int) -> None:
    """pymoo's NSGA-II crowding ('cd') divides Deb's sum by M; every front, copies included."""
    values = points(seed)
    ranks = pareto.nondominated_ranks(values)
    crowding = get_crowding_function("cd")
    for rank in np.unique(ranks):
        front = values[ranks == rank]
        expected = crowding.do(-front) * values.shape[1]
        np.testing.assert_allclose(pareto.crowding_distance(front), expected, rtol=1e-12)


@pytest.mark.parametrize("seed", SEEDS)
def test_hypervolume_equals_pymoo(seed: int) -> None:
    values = points(seed)
    below_all = values.min(axis=0) - 1.0
    through_the_middle = np.median(values, axis=0)  # some rows lie outside or on its planes
    for reference in (below_all, through_the_middle, values[seed % len(values)]):
        expected = HV(ref_point=-reference).do(-values)
        assert pareto.hypervolume(values, reference) == pytest.approx(expected, rel=1e-10)


@pytest.mark.parametrize("seed", SEEDS)
def test_the_two_objective_shortcuts_equal_the_general_sort(seed: int) -> None:
    """A constant third objective changes no dominance; it sends the rows down the M > 2 path."""
    values = points(seed)[:, :2]
    widened = np.column_stack([values, np.zeros(len(values))])
    ranks = pareto.nondominated_ranks(values)
    np.testing.assert_array_equal(ranks, pareto.nondominated_ranks(widened))
    np.testing.assert_array_equal(pareto.nondominated_mask(values), ranks == 0)
    np.testing.assert_array_equal(pareto.nondominated_mask(widened), ranks == 0)


def test_copies_share_a_front_and_a_dominated_row_is_one_front_behind() -> None:
    values = np.array([[1.0, 1.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.0], [0.0, 0.0]])
    np.testing.assert_array_equal(pareto.nondominated_ranks(values), [0, 0, 1, 0, 2])
    assert pareto.dominates([1, 1], [0, 1]) and not pareto.dominates([1, 1], [1, 1])


def test_the_domination_matrix_is_dominance_pair_by_pair() -> None:
    values = np.random.default_rng(5).integers(0, 3, size=(60, 3)).astype(float)  # many copies
    values[7] = np.nan
    expected = [[pareto.dominates(a, b) for b in values] for a in values]
    np.testing.assert_array_equal(pareto.domination_matrix(values), expected)


def test_the_front_of_many_rows_in_three_objectives_spans_several_blocks() -> None:
    rng = np.random.default_rng(7)
    values = rng.normal(size=(1500, 3))  # three blocks of 512 rows
    expected = ~pareto.domination_matrix(values).any(axis=0)
    np.testing.assert_array_equal(pareto.nondominated_mask(values), expected)


@pytest.mark.parametrize(
    ("values", "reference", "volume"),
    [
        ([[1, 3], [2, 2], [3, 1]], [0, 0], 6.0),  # a staircase: 1x3 + 1x2 + 1x1
        ([[1, 3], [2, 2], [3, 1], [1, 1], [2, 2]], [0, 0], 6.0),  # a dominated row, a copy
        ([[4, 5]], [1, 1], 12.0),  # one box
        ([[4, 5], [0, 9]], [1, 1], 12.0),  # a row no better than the reference adds nothing
        ([[4, 5], [9, 1]], [1, 1], 12.0),  # nor one equal to it in an objective
        ([[2, 1, 1], [1, 2, 1], [1, 1, 2]], [0, 0, 0], 4.0),  # three unit slabs over a cube
        ([[1, 1, 1, 1], [2, 0.5, 1, 1]], [0, 0, 0, 0], 1.5),  # two overlapping 4-D boxes
        ([[-1, -2], [-2, -1]], [-3, -3], 3.0),  # negated minimised measures
    ],
)
def test_hypervolume_of_hand_made_fronts(values: list, reference: list, volume: float) -> None:
    assert pareto.hypervolume(np.array(values, dtype=float), reference) == pytest.approx(volume)


def test_crowding_ends_are_infinite_and_a_flat_objective_adds_nothing() -> None:
    front = np.array([[0.0, 5.0], [1.0, 5.0], [3.0, 5.0], [4.0, 5.0]])
    np.testing.assert_array_equal(pareto.crowding_distance(front), [np.inf, 0.75, 0.75, np.inf])
    np.testing.assert_array_equal(pareto.crowding_distance(front[:2]), [np.inf, np.inf])
    np.testing.assert_array_equal(pareto.crowding_distance(np.ones((3, 2))), [0.0, 0.0, 0.0])


def test_failed_rows_rank_last_are_on_no_front_and_add_no_volume() -> None:
    values = np.array([[1.0, 0.0], [np.nan, 5.0], [0.0, 1.0], [0.0, 0.0]])
    np.testing.assert_array_equal(pareto.nondominated_ranks(values), [0, 2, 0, 1])
    np.testing.assert_array_equal(pareto.nondominated_mask(values), [True, False, True, False])
    assert pareto.hypervolume(values, [-1, -1]) == pytest.approx(3.0)
    order = pareto.nsga2_order(values, keys=np.arange(4))
    assert order[-1] == 1


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: pareto.nondominated_ranks(np.ones(3)), r"\[N, M\]"),
        (lambda: pareto.nondominated_ranks([[np.inf, 1.0]]), "infinite"),
        (lambda: pareto.crowding_distance([[np.nan, 1.0]]), "NaN"),
        (lambda: pareto.hypervolume([[1.0, 1.0]], [0.0]), "reference"),
        (lambda: pareto.nsga2_order(np.ones((2, 2)), keys=[1, 1]), "keys must be unique"),
        (lambda: pareto.afpo_select([1], np.ones((2, 1)), 1, keys=[0, 1]), "ages"),
        (lambda: pareto.binary_tournament(np.random.default_rng(0), [0, 0], 2), "order"),
    ],
)
def test_bad_input_is_refused_in_one_line(call, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        call()


def test_nsga2_order_is_rank_then_crowding_then_keys() -> None:
    values = np.array([[0.0, 3.0], [1.0, 2.0], [2.0, 1.0], [3.0, 0.0], [1.0, 1.0], [1.0, 1.0]])
    keys = np.array([[0, 5], [0, 4], [0, 3], [0, 2], [1, 1], [0, 9]])
    # front 0: the ends (rows 0 and 3, infinite) by key, then rows 2 and 1 (equal crowding) by
    # key; front 1: the two copies by key
    np.testing.assert_array_equal(pareto.nsga2_order(values, keys), [3, 0, 2, 1, 5, 4])


@pytest.mark.parametrize("seed", range(5))
def test_nsga2_order_does_not_depend_on_the_rows_order(seed: int) -> None:
    values, rng = points(seed), np.random.default_rng(seed)
    keys = np.column_stack([rng.integers(0, 3, len(values)), np.arange(len(values))])
    shuffled = rng.permutation(len(values))
    order = pareto.nsga2_order(values, keys)
    assert sorted(order) == list(range(len(values)))
    np.testing.assert_array_equal(
        shuffled[pareto.nsga2_order(values[shuffled], keys[shuffled])], order
    )
    ranks = pareto.nondominated_ranks(values)[order]
    assert (np.diff(ranks) >= 0).all()


def test_binary_tournament_takes_the_earlier_of_two_draws() -> None:
    order = np.array([4, 2, 0, 1, 3])  # row 4 is the best, row 3 the worst
    rng, same = np.random.default_rng(11), np.random.default_rng(11)
    parents = pareto.binary_tournament(rng, order, 200)
    pairs = same.integers(0, 5, size=(200, 2))
    rank_of = {row: position for position, row in enumerate(order)}
    expected = [min(pair, key=rank_of.__getitem__) for pair in pairs.tolist()]
    np.testing.assert_array_equal(parents, expected)
    assert rng.integers(0, 2**62) == same.integers(0, 2**62)  # one draw, no more
    assert 3 not in parents or (pairs == 3).all(axis=1).any()


def test_afpo_keeps_the_young_and_the_fit_and_breaks_the_last_layer_by_fitness() -> None:
    ages = np.array([0, 5, 5, 1, 0, 9])
    fitness = np.array([[1.0], [9.0], [4.0], [2.0], [1.0], [9.0]])
    keys = np.arange(6)
    # layers on (youth, fitness): {0, 4, 1, 3} (row 4 copies row 0), then {2, 5}
    np.testing.assert_array_equal(pareto.afpo_select(ages, fitness, 6, keys), [1, 3, 0, 4, 5, 2])
    np.testing.assert_array_equal(pareto.afpo_select(ages, fitness, 3, keys), [1, 3, 0])
    np.testing.assert_array_equal(pareto.afpo_select(ages, fitness, 5, keys), [1, 3, 0, 4, 5])
    assert len(pareto.afpo_select(ages, fitness, 0, keys)) == 0


def test_afpo_does_not_depend_on_the_rows_order_and_puts_failures_last() -> None:
    rng = np.random.default_rng(3)
    ages, values = rng.integers(0, 4, 40), rng.integers(0, 3, size=(40, 2)).astype(float)
    values[[5, 17]] = np.nan
    keys, shuffled = np.arange(40), rng.permutation(40)
    chosen = pareto.afpo_select(ages, values, 40, keys)
    again = shuffled[pareto.afpo_select(ages[shuffled], values[shuffled], 40, keys[shuffled])]
    np.testing.assert_array_equal(chosen, again)
    assert set(chosen[-2:]) == {5, 17}
