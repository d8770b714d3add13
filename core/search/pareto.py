"""Pareto mathematics for several objectives at once: dominance, non-dominated ranks, crowding
distance, hypervolume, NSGA-II's total order and tournament, and AFPO's age-fitness selection.

Pure numpy functions on an [N, M] float array of objective values (N individuals, M objectives),
all for MAXIMISATION: a caller negates every measure it minimises (`-cost_of_transport`) before
calling. Point `a` dominates `b` when it is at least as good in every objective and strictly
better in one; identical points do not dominate each other, so they share a front.

A row holding NaN in any objective is a failed evaluation (softevo never scores a failure 0): it
is on no front, dominates nothing, is ranked after every finite row and adds no hypervolume.
Infinite values are refused. Every tie is broken by the caller's `keys` (e.g. an individual's
(generation, index)), never by the order in which results arrived. `docs/evolution.md` gives the
definitions; `tests/core/search/test_pareto.py` checks them against pymoo.
"""

from __future__ import annotations

import bisect

import numpy as np

#: rows compared at once by `nondominated_mask` (memory ~ block x front x M bytes)
_BLOCK = 512


def _as_values(values: np.ndarray, name: str = "values") -> np.ndarray:
    """The objective values as a float [N, M] array; refuses other shapes and infinities."""
    array = np.asarray(values, dtype=float)
    if array.ndim != 2 or array.shape[1] < 1:
        raise ValueError(f"{name} must be an [N, M] array with M >= 1, got shape {array.shape}")
    if np.isinf(array).any():
        raise ValueError(f"{name} holds an infinite value (NaN marks a failed evaluation)")
    return array


def _as_keys(keys: np.ndarray, n: int) -> np.ndarray:
    """The tie-break keys as an [N, K] array of unique rows (the first column counts most)."""
    array = np.asarray(keys)
    if array.ndim == 1:
        array = array[:, None]
    if array.ndim != 2 or len(array) != n:
        raise ValueError(f"keys must be [N] or [N, K] with N = {n}, got shape {array.shape}")
    if n and len(np.unique(array, axis=0)) != n:
        raise ValueError("keys must be unique per individual, e.g. (generation, index)")
    return array


def _key_order(keys: np.ndarray) -> np.ndarray:
    """Row indices sorted by the keys ascending, first column first."""
    return np.lexsort(keys.T[::-1]) if keys.shape[1] else np.arange(len(keys))


def dominates(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether `a` Pareto-dominates `b` ([M] each, maximised): >= everywhere, > somewhere."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return bool(np.all(a >= b) and np.any(a > b))


def domination_matrix(values: np.ndarray) -> np.ndarray:
    """[N, N] bool, [i, j] true when row i dominates row j. O(M N^2) time, N^2 bytes per
    temporary: meant for populations (thousands), not for the whole history of a run."""
    array = _as_values(values)
    n = len(array)
    at_least, scratch = np.ones((n, n), dtype=bool), np.empty((n, n), dtype=bool)
    for column in array.T:  # one objective at a time keeps the temporaries at N^2
        np.greater_equal(column[:, None], column[None, :], out=scratch)
        at_least &= scratch
    # i >= j everywhere dominates unless j >= i everywhere too, i.e. unless they are copies (a
    # cheaper test than the transpose); NaN compares false: a failed row dominates none
    copy_of = np.unique(array, axis=0, return_inverse=True)[1].ravel()
    np.not_equal(copy_of[:, None], copy_of[None, :], out=scratch)
    at_least &= scratch
    return at_least


def nondominated_ranks(values: np.ndarray) -> np.ndarray:
    """Front of every row ([N] int, 0 = non-dominated), by Deb et al.'s (2002) fast
    non-dominated sorting. Failed (NaN) rows all get the rank after the last finite front."""
    array = _as_values(values)
    ranks = np.full(len(array), -1, dtype=np.int64)
    finite = np.flatnonzero(~np.isnan(array).any(axis=1))
    if array.shape[1] == 2:
        ranks[finite] = _ranks_2d(array[finite])
        ranks[ranks < 0] = ranks.max(initial=-1) + 1
        return ranks
    dominating = domination_matrix(array[finite])
    dominated_by = dominating.sum(axis=0)  # how many rows dominate each row
    local = np.full(len(finite), -1, dtype=np.int64)
    front, level = np.flatnonzero(dominated_by == 0), 0
    while front.size:
        local[front] = level
        dominated_by -= dominating[front].sum(axis=0)
        front, level = np.flatnonzero((dominated_by == 0) & (local < 0)), level + 1
    ranks[finite] = local
    ranks[ranks < 0] = level  # failed rows: one front after the others
    return ranks


def _ranks_2d(array: np.ndarray) -> np.ndarray:
    """The ranks of finite [N, 2] rows in O(N log N) (Jensen 2003): taken best first in the
    first objective, a row joins the first front whose latest row (the front's highest second
    objective so far; these fall from front to front) does not dominate it."""
    ranks = np.empty(len(array), dtype=np.int64)
    order = np.lexsort((-array[:, 1], -array[:, 0])).tolist()
    firsts, seconds = array[:, 0].tolist(), array[:, 1].tolist()
    latest_negated: list[float] = []  # -second objective of each front's latest row, ascending
    latest: list[tuple[float, float]] = []
    for row in order:
        point = (firsts[row], seconds[row])
        front = bisect.bisect_right(latest_negated, -point[1])  # first front below the row
        if front and latest[front - 1] == point:  # a copy of a front's latest row joins it
            front -= 1
        elif front == len(latest):
            latest_negated.append(-point[1])
            latest.append(point)
        else:
            latest_negated[front], latest[front] = -point[1], point
        ranks[row] = front
    return ranks


def nondominated_mask(values: np.ndarray) -> np.ndarray:
    """[N] bool: the rows on the first front (none of them failed), for any N: rows are taken in
    lexicographic order, best first, so a row can only be dominated by one before it, and each
    block of rows is checked against the front so far and itself. Time ~ N x front x M."""
    array = _as_values(values)
    mask = np.zeros(len(array), dtype=bool)
    finite = np.flatnonzero(~np.isnan(array).any(axis=1))
    ordered = finite[np.lexsort((-array[finite]).T[::-1])]  # first objective first, descending
    if array.shape[1] == 2:
        mask[ordered[_first_front_2d(array[ordered])]] = True
        return mask
    front = np.empty((0, array.shape[1]))
    for start in range(0, len(ordered), _BLOCK):
        rows = ordered[start : start + _BLOCK]
        block = array[rows]
        beaten = _dominated_by_any(front, block) | domination_matrix(block).any(axis=0)
        kept = rows[~beaten]
        mask[kept] = True
        front = np.concatenate([front, array[kept]])
    return mask


def _first_front_2d(ordered: np.ndarray) -> np.ndarray:
    """[N] bool for [N, 2] rows sorted best first: a row is on the front when its second
    objective beats that of every row before it other than its own copies (which come just
    before it)."""
    new_point = np.ones(len(ordered), dtype=bool)
    new_point[1:] = (ordered[1:] != ordered[:-1]).any(axis=1)
    copies_start = np.maximum.accumulate(np.where(new_point, np.arange(len(ordered)), 0))
    best_second = np.concatenate([[-np.inf], np.maximum.accumulate(ordered[:, 1])])
    return ordered[:, 1] > best_second[copies_start]


def _dominated_by_any(front: np.ndarray, block: np.ndarray) -> np.ndarray:
    """[len(block)] bool: whether some row of `front` dominates each row of `block`."""
    if not len(front):
        return np.zeros(len(block), dtype=bool)
    at_least = (front[:, None, :] >= block[None, :, :]).all(axis=2)
    better = (front[:, None, :] > block[None, :, :]).any(axis=2)
    return np.asarray((at_least & better).any(axis=0), dtype=bool)


def crowding_distance(values: np.ndarray) -> np.ndarray:
    """NSGA-II's crowding distance of the rows of ONE front ([N] float, larger = lonelier).

    Per objective, the rows are sorted best first (ties keep their row order); the first and last
    get infinity, every other row the gap between its two neighbours divided by the objective's
    range within the front; an objective whose range is 0 adds 0 to every row (its ends too).
    The sum over objectives is Deb's; pymoo divides it by M (the same order). A front of one or
    two rows is all infinity (every row is an end), as in pymoo. Duplicates are not merged: the
    tie order decides which copy is the end, so callers pass rows in key order (`nsga2_order`).
    """
    array = _as_values(values)
    if np.isnan(array).any():
        raise ValueError("values holds NaN: the crowding distance is for a front of finite rows")
    n = len(array)
    if n <= 2:
        return np.full(n, np.inf)
    distance = np.zeros(n)
    for column in array.T:
        order = np.argsort(-column, kind="stable")  # best first, ties in row order
        span = column.max() - column.min()
        if span == 0:
            continue
        gaps = -np.diff(column[order]) / span  # [n-1], >= 0
        distance[order[1:-1]] += gaps[:-1] + gaps[1:]
        distance[order[[0, -1]]] = np.inf
    return distance


def hypervolume(values: np.ndarray, reference: np.ndarray) -> float:
    """The volume dominated by the rows and bounded by `reference` ([M]), exact for any M.

    Only rows strictly better than the reference in every objective count (one that only equals
    it somewhere spans no volume); failed rows count for nothing. A sweep for M <= 2; above, the
    front is sliced along its last objective (HSO) and each slice is an (M-1)-objective volume,
    O(N^(M-1) log N): fine for the fronts of a population, not for hundreds of objectives."""
    array = _as_values(values)
    ref = np.asarray(reference, dtype=float)
    if ref.shape != (array.shape[1],) or not np.isfinite(ref).all():
        raise ValueError(f"reference must be {array.shape[1]} finite numbers, got {reference!r}")
    better = array[(array > ref).all(axis=1)]  # NaN compares false
    if not len(better):
        return 0.0
    front = np.unique(better[nondominated_mask(better)], axis=0) - ref
    return float(_volume(front))


#: How far past the nadir the normalised reference lies, as a fraction of each objective's
#: range: a front's extreme points (which lie on the nadir in one objective) still count.
NADIR_MARGIN = 0.1


def normalised_hypervolume(values: np.ndarray, ideal: np.ndarray, nadir: np.ndarray) -> float:
    """The hypervolume of the rows with each objective scaled to [0, 1] between `nadir` (0)
    and `ideal` (1) (maximised, [M] each; values past the ideal clipped to it), against a
    reference `NADIR_MARGIN` of the range past the nadir, divided by the box's volume: 1 is a
    front that holds the ideal point, and every objective weighs the same whatever its units
    (a raw volume against a far reference is nearly the best value of one objective)."""
    array = _as_values(values)
    top, bottom = np.asarray(ideal, dtype=float), np.asarray(nadir, dtype=float)
    if top.shape != (array.shape[1],) or bottom.shape != top.shape:
        raise ValueError(f"ideal and nadir must be {array.shape[1]} numbers each")
    if not (np.isfinite(top).all() and np.isfinite(bottom).all() and (top > bottom).all()):
        raise ValueError(f"ideal must be finite and above nadir, got {ideal!r} and {nadir!r}")
    with np.errstate(over="ignore", invalid="ignore"):  # a range near 0 or past the floats
        scaled = (array - bottom) / (top - bottom)
    # past the ideal counts as it; at or past the reference counts for nothing, so a value
    # far beyond it (or one that overflowed) is the reference itself: the volume is the same
    scaled = np.clip(scaled, -NADIR_MARGIN, 1.0)
    reference = np.full(array.shape[1], -NADIR_MARGIN)
    return hypervolume(scaled, reference) / (1.0 + NADIR_MARGIN) ** array.shape[1]


def _volume(points: np.ndarray) -> float:
    """The volume of the union of boxes [0, p] for positive [N, M] points."""
    if points.shape[1] == 1:
        return float(points[:, 0].max())
    order = np.argsort(-points[:, -1], kind="stable")
    depth = points[order, -1]
    rest = points[order, :-1]
    slabs = depth - np.append(depth[1:], 0.0)  # slab k: covered by the first k+1 points' rest
    if points.shape[1] == 2:
        return float(np.dot(slabs, np.maximum.accumulate(rest[:, 0])))
    total = 0.0
    for k in np.flatnonzero(slabs > 0):
        section = rest[: k + 1]
        if section.shape[1] > 2:  # the 2-D sweep takes dominated points as they are
            section = section[nondominated_mask(section)]
        total += slabs[k] * _volume(section)
    return total


def nsga2_order(values: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Every row once, best first ([N] int): NSGA-II's crowded comparison made a total order.

    Front rank ascending, then crowding distance within the front descending, then `keys`
    ascending (e.g. (generation, index), first column first; unique per row). Crowding is
    computed with rows in key order, so the result never depends on the rows' order. Failed rows
    come last, in key order. Survivors of a (mu + lambda) step are `order[:mu]`."""
    array = _as_values(values)
    by_key = _key_order(_as_keys(keys, len(array)))
    sorted_values = array[by_key]
    ranks = nondominated_ranks(sorted_values)
    crowding = np.zeros(len(array))
    finite = ~np.isnan(sorted_values).any(axis=1)
    for rank in np.unique(ranks[finite]):
        members = np.flatnonzero(ranks == rank)
        crowding[members] = crowding_distance(sorted_values[members])
    positions = np.arange(len(array))  # key order, the last tie-breaker
    return by_key[np.lexsort((positions, -crowding, ranks))]


def binary_tournament(rng: np.random.Generator, order: np.ndarray, n: int) -> np.ndarray:
    """`n` parents ([n] int, row indices), each the better of two rows drawn uniformly with
    replacement; better = earlier in `order` (best first, e.g. `nsga2_order`'s), so ties cannot
    happen. Draws exactly one `rng.integers(0, N, size=(n, 2))`."""
    order = np.asarray(order)
    if n < 0 or (n and not len(order)):
        raise ValueError(f"cannot draw {n} parents from {len(order)} individuals")
    if not np.array_equal(np.sort(order), np.arange(len(order))):
        raise ValueError("order must hold every row index once (best first), as nsga2_order gives")
    position = np.empty(len(order), dtype=np.int64)
    position[order] = np.arange(len(order))
    pairs = rng.integers(0, len(order), size=(n, 2))
    first_wins = position[pairs[:, 0]] < position[pairs[:, 1]]
    return np.where(first_wins, pairs[:, 0], pairs[:, 1])


def afpo_select(ages: np.ndarray, values: np.ndarray, n: int, keys: np.ndarray) -> np.ndarray:
    """AFPO survivors (Schmidt & Lipson 2010): `n` row indices, in order of preference.

    Pareto layers on (-age, each objective), younger being better: whole layers are kept while
    they fit, as evosoro does. Evosoro fills the last layer at random, favouring the front of its
    sort by objective importance; here that preference is exact: the last layer's rows by the
    first objective descending, then the next ones, then younger, then `keys` ascending. Failed
    (NaN) rows form the last layer. Every row is returned when n >= N."""
    array = _as_values(values)
    age = np.asarray(ages, dtype=float)
    if age.shape != (len(array),) or not np.isfinite(age).all():
        raise ValueError(f"ages must be {len(array)} finite numbers, one per individual")
    if n < 0:
        raise ValueError(f"n must be >= 0, got {n}")
    key_rows = _as_keys(keys, len(array))
    layers = nondominated_ranks(np.column_stack([-age, array]))
    worst_first = np.where(np.isnan(array), -np.inf, array)  # failed rows after finite ones
    positions = np.empty(len(array), dtype=np.int64)
    positions[_key_order(key_rows)] = np.arange(len(array))
    sort_keys = (positions, age, *(-worst_first[:, ::-1]).T, layers)  # lexsort: last key first
    return np.lexsort(sort_keys)[:n]
