"""GA operators: each property stated in the docs, checked on many random cases."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from softevo.core.robots.genome import Genome
from softevo.core.robots.genome import gene_diversity as diversity
from softevo.core.search import operators

seeds = st.integers(0, 2**32 - 1)


@given(seeds, st.integers(2, 60))
def test_two_point_crossover_takes_genes_only_from_parents_at_the_cuts(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    a, b = np.arange(n), np.arange(n) + 1000  # every gene tells which parent it came from
    first, second, (i, j) = operators.two_point_crossover(a, b, rng)
    assert 0 <= i < j <= n
    np.testing.assert_array_equal(first, np.concatenate([a[:i], b[i:j], a[j:]]))
    np.testing.assert_array_equal(second, np.concatenate([b[:i], a[i:j], b[j:]]))


@given(seeds, st.sampled_from([2, 3, 5, 28, 64, 131, 20_000]), st.integers(0, 3))
def test_cut_points_are_drawn_as_numpy_choice_draws_them(seed: int, n: int, before: int) -> None:
    """The same points and the same generator state after as `np.sort(rng.choice(n + 1, 2,
    replace=False))`, which bred every curve so far (`before` draws first, some leaving half of
    a 64-bit draw buffered)."""
    ours, numpy = np.random.default_rng(seed), np.random.default_rng(seed)
    for rng in (ours, numpy):
        for _ in range(before):
            rng.integers(0, 7)
    expected = tuple(int(v) for v in np.sort(numpy.choice(n + 1, size=2, replace=False)))
    assert operators.two_cut_points(n, ours) == expected
    assert ours.bit_generator.state == numpy.bit_generator.state


def test_two_point_crossover_cut_points_cover_every_position() -> None:
    rng = np.random.default_rng(0)
    cuts = {operators.two_point_crossover(np.zeros(5), np.ones(5), rng)[2] for _ in range(2000)}
    assert cuts == {(i, j) for i in range(6) for j in range(i + 1, 6)}


@given(seeds, st.integers(1, 40), st.integers(0, 10), st.integers(2, 5))
def test_mutation_changes_exactly_the_stated_number_of_genes(
    seed: int, n: int, n_genes: int, alphabet_size: int
) -> None:
    rng = np.random.default_rng(seed)
    alphabet = np.full(n, alphabet_size)
    genes = rng.integers(0, alphabet_size, n)
    child = operators.mutate_discrete(genes, alphabet, n_genes, rng)
    assert int((child != genes).sum()) == min(n_genes, n)
    assert np.all((child >= 0) & (child < alphabet_size))


def test_mutation_skips_genes_that_cannot_change() -> None:
    rng = np.random.default_rng(1)
    alphabet = np.array([1, 1, 4, 1])
    child = operators.mutate_discrete(np.zeros(4, dtype=int), alphabet, 3, rng)
    assert child.tolist()[0:2] == [0, 0] and child[3] == 0 and child[2] != 0


@given(seeds)
def test_real_mutation_stays_in_bounds(seed: int) -> None:
    rng = np.random.default_rng(seed)
    bounds = np.array([[-1.0, 1.0], [-math.pi / 2, math.pi / 2], [-2 * math.pi, 2 * math.pi]])
    genes = rng.uniform(bounds[:, 0], bounds[:, 1])
    child = operators.mutate_real(genes, bounds, 0.5, rng)
    assert np.all(child >= bounds[:, 0]) and np.all(child <= bounds[:, 1])
    assert np.any(child != genes)


@given(seeds, st.integers(2, 40), st.integers(1, 6), st.sampled_from([0.2, 0.5, 0.75]))
def test_grouped_truncation_keeps_the_stated_fraction_of_each_group(
    seed: int, n: int, groups: int, fraction: float
) -> None:
    rng = np.random.default_rng(seed)
    fitness = rng.random(n)
    kept = operators.grouped_truncation(fitness, groups, fraction, np.random.default_rng(seed))
    # The same shuffle the operator made, to know the groups.
    order = np.random.default_rng(seed).permutation(n)
    expected = []
    for group in np.array_split(order, min(groups, n)):
        keep = max(1, math.floor(fraction * len(group) + 0.5))
        expected.extend(group[np.argsort(-fitness[group])[:keep]])
    assert sorted(kept.tolist()) == sorted(int(i) for i in expected)
    assert len(set(kept.tolist())) == len(kept)
    assert int(np.argmax(fitness)) in kept.tolist()  # the overall best always survives
    assert np.all(np.diff(fitness[kept]) <= 0)  # best first


def test_failed_individuals_rank_last_and_are_never_chosen_over_a_real_one() -> None:
    fitness = np.array([0.1, math.nan, 0.0, math.nan, 0.3])
    assert operators.rank_order(fitness).tolist() == [4, 0, 2, 1, 3]
    rng = np.random.default_rng(0)
    winners = operators.tournament(fitness, 2000, 5, rng)
    # A failed individual wins only a tournament of failed entrants: 0.4**5 = 1 % of them.
    assert np.isnan(fitness[winners]).mean() < 0.03
    picks = operators.roulette(fitness, 500, rng)
    assert not np.isnan(fitness[picks]).any()
    kept = operators.grouped_truncation(fitness, 1, 0.4, rng)
    assert kept.tolist() == [4, 0]


def test_roulette_prefers_fitter_individuals() -> None:
    fitness = np.array([0.0, 1.0, 3.0])
    picks = operators.roulette(fitness, 4000, np.random.default_rng(0))
    counts = np.bincount(picks, minlength=3) / 4000
    assert counts[0] == 0  # weight fitness - min: the worst gets nothing
    assert abs(counts[2] - 0.75) < 0.03 and abs(counts[1] - 0.25) < 0.03


def test_tournament_of_size_one_is_uniform_and_large_tournaments_pick_the_best() -> None:
    fitness = np.arange(10.0)
    rng = np.random.default_rng(0)
    assert len(set(operators.tournament(fitness, 500, 1, rng).tolist())) == 10
    assert np.mean(operators.tournament(fitness, 500, 8, rng) >= 7) > 0.9


@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 8),
    st.integers(1, 8),
    st.lists(
        st.sampled_from([0.0, 1.0, 2.0, math.nan, -math.inf, math.inf]), min_size=1, max_size=9
    ),
)
def test_few_entrants_pick_the_winners_numpy_picks_by_the_same_draws(
    seed: int, n: int, size: int, values: list[float]
) -> None:
    """The Python path for a few entrants (steady-state's births) against numpy's argmax: the
    same winners (NaN lowest, ties to the first drawn) and the generator left the same."""
    fitness = np.array(values)
    fast, slow = np.random.default_rng(seed), np.random.default_rng(seed)
    winners = operators.tournament(fitness, n, size, fast)
    entrants = slow.integers(0, len(fitness), size=(n, size))
    key = np.where(np.isnan(fitness[entrants]), -np.inf, fitness[entrants])
    assert winners.tolist() == entrants[np.arange(n), np.argmax(key, axis=1)].tolist()
    assert fast.random() == slow.random()


@pytest.mark.parametrize("seed", range(5))
def test_diversity_is_the_mean_pairwise_normalised_hamming_distance(seed: int) -> None:
    """Counted from value counts in one pass; checked here pair by pair, as it is defined."""
    rng = np.random.default_rng(seed)
    population = rng.integers(0, 5, size=(int(rng.integers(2, 12)), int(rng.integers(1, 40))))
    genomes = [Genome("voxel", tuple(int(g) for g in row)) for row in population]
    pairs = list(itertools.combinations(population, 2))
    expected = sum(np.mean(a != b) for a, b in pairs) / len(pairs)
    assert diversity(genomes) == pytest.approx(expected, rel=1e-12)
