"""Genetic operators as small pure functions. The random generator is always passed in.

Fitness arrays may hold NaN (a failed evaluation): every selection ranks NaN last and gives it no
roulette weight; nothing here treats a failure as a score of 0.
"""

from __future__ import annotations

import math

import numpy as np


def rank_order(fitness: np.ndarray) -> np.ndarray:
    """Indices from best to worst; NaN last; ties keep index order (stable)."""
    key = np.where(np.isnan(fitness), -np.inf, fitness)
    return np.argsort(-key, kind="stable")


def two_point_crossover(
    a: np.ndarray, b: np.ndarray, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """The paper's two-point crossover: genes [0, i) and [j, n) from one parent, [i, j) from the
    other, with 0 <= i < j <= n drawn uniformly. Returns both children and the cut points."""
    n = len(a)
    if n != len(b):
        raise ValueError(f"parents differ in length: {n} and {len(b)}")
    if n < 2:
        return a.copy(), b.copy(), (0, n)
    i, j = two_cut_points(n, rng)
    first, second = a.copy(), b.copy()
    first[i:j], second[i:j] = b[i:j], a[i:j]
    return first, second, (i, j)


def two_cut_points(n: int, rng: np.random.Generator) -> tuple[int, int]:
    """Two distinct points of 0..n, ascending, drawn exactly as
    `np.sort(rng.choice(n + 1, size=2, replace=False))` draws them (numpy's Floyd sampling: one
    of 0..n-1, one of 0..n that becomes n if it repeats the first; then its shuffle's draw, whose
    order the sort undoes), the generator left in the same state: a third of the cost, and every
    curve bred before stays the same (`tests/core/search/test_operators.py` checks both)."""
    first, second = int(rng.integers(0, n)), int(rng.integers(0, n + 1))
    if second == first:
        second = n
    rng.integers(0, 2)  # the shuffle's draw
    return (first, second) if first < second else (second, first)


def mutate_discrete(
    genes: np.ndarray, alphabet: np.ndarray, n_genes: int, rng: np.random.Generator
) -> np.ndarray:
    """Redraw `n_genes` distinct genes, each to a value different from its old one (genes whose
    alphabet has one value cannot change and are never picked)."""
    child = genes.copy()
    changeable = np.flatnonzero(alphabet > 1)
    picked = rng.choice(changeable, size=min(n_genes, len(changeable)), replace=False)
    for position in picked:
        shift = rng.integers(1, alphabet[position])  # 1 .. alphabet-1: never the old value
        child[position] = (child[position] + shift) % alphabet[position]
    return child


def mutate_real(
    genes: np.ndarray, bounds: np.ndarray, sigma: float, rng: np.random.Generator
) -> np.ndarray:
    """Bounded Gaussian step: each gene moves by N(0, sigma * (high - low)), clipped to bounds."""
    if len(genes) == 0:
        return genes.copy()
    low, high = bounds.T
    return np.clip(genes + rng.normal(0.0, sigma * (high - low)), low, high)


def grouped_truncation(
    fitness: np.ndarray, groups: int, fraction: float, rng: np.random.Generator
) -> np.ndarray:
    """The paper's selection: shuffle the population into `groups` near-equal groups and keep the
    best `fraction` of each (at least one; half rounds up). Returns kept indices, best first."""
    order = rng.permutation(len(fitness))
    kept: list[int] = []
    for group in np.array_split(order, min(groups, len(fitness))):
        keep = max(1, int(np.floor(fraction * len(group) + 0.5)))
        kept.extend(group[rank_order(fitness[group])[:keep]].tolist())
    kept_array = np.array(kept, dtype=np.int64)
    return kept_array[rank_order(fitness[kept_array])]


#: Up to this many entrants, `tournament` compares them in Python: a steady-state birth's two
#: tournaments would otherwise pay numpy's per-call overhead (indexing, where, argmax) each.
FEW_ENTRANTS = 16


def tournament(fitness: np.ndarray, n: int, size: int, rng: np.random.Generator) -> np.ndarray:
    """`n` winners, each the best of `size` individuals drawn uniformly (NaN loses; of equals,
    the first drawn), by the same draws however many there are."""
    entrants = rng.integers(0, len(fitness), size=(n, size))
    if entrants.size <= FEW_ENTRANTS:
        return np.array([_best_of(fitness, row) for row in entrants.tolist()], dtype=np.int64)
    key = fitness[entrants]  # only the entrants (2 x size values, not the population's P)
    key = np.where(np.isnan(key), -np.inf, key)
    return entrants[np.arange(n), np.argmax(key, axis=1)]


def _best_of(fitness: np.ndarray, drawn: list[int]) -> int:
    """The first of `drawn` with the highest fitness, NaN lowest (`np.argmax`'s choice)."""
    best, top = drawn[0], -math.inf
    for index in drawn:
        value = float(fitness[index])
        if value > top:  # NaN never is; a first -inf or NaN keeps drawn[0], as argmax does
            best, top = index, value
    return best


def roulette(fitness: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """`n` picks with probability proportional to fitness above the worst finite fitness (a
    failed individual has weight 0); uniform when every weight is 0."""
    finite = np.isfinite(fitness)
    weights = np.zeros(len(fitness))
    if finite.any():
        weights[finite] = fitness[finite] - fitness[finite].min()
    if weights.sum() <= 0:
        weights = finite.astype(float) if finite.any() else np.ones(len(fitness))
    return rng.choice(len(fitness), size=n, p=weights / weights.sum())


def mutate_each(
    genes: np.ndarray, alphabet: np.ndarray, rate: float, rng: np.random.Generator
) -> np.ndarray:
    """Per-gene mutation: each gene is redrawn with probability `rate` (one draw per gene,
    whatever its alphabet), to a value different from its old one; a gene whose alphabet has
    one value never changes. Children walk as far as `rate` x genes labels a step."""
    child = genes.copy()
    hit = (rng.random(len(genes)) < rate) & (alphabet > 1)
    sizes = alphabet[hit]
    child[hit] = (child[hit] + rng.integers(1, sizes, size=len(sizes))) % sizes
    return child


def iso_line(
    x: np.ndarray,
    y: np.ndarray,
    bounds: np.ndarray,
    sigma_iso: float,
    sigma_line: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """Iso-line variation (Vassiliades & Mouret 2018): x + sigma_iso N(0, I) (high - low) +
    sigma_line N(0, 1) (y - x), clipped to bounds. The second term steps along the line through
    two elites (one draw for every gene), where good genomes of different cells tend to lie;
    the first is a small isotropic step of each gene's range."""
    if len(x) == 0:
        return x.copy()
    low, high = bounds.T
    isotropic = rng.normal(0.0, 1.0, len(x)) * sigma_iso * (high - low)
    along = rng.normal(0.0, 1.0) * sigma_line * (y - x)
    return np.clip(x + isotropic + along, low, high)


def mutate_real_each(
    genes: np.ndarray, bounds: np.ndarray, rate: float, sigma: float, rng: np.random.Generator
) -> np.ndarray:
    """Per-gene Gaussian step: each real gene moves with probability `rate` by N(0, sigma x
    (high - low)), clipped to bounds (two draws per gene: whether, and how far)."""
    if len(genes) == 0:
        return genes.copy()
    low, high = bounds.T
    hit = rng.random(len(genes)) < rate
    step = rng.normal(0.0, 1.0, len(genes)) * sigma * (high - low)
    return np.clip(np.where(hit, genes + step, genes), low, high)
