"""How the coordinator cuts a generation's new robots into batches (`split_evenly`)."""

from __future__ import annotations

import pytest

from softevo.core.evaluator import split_evenly


@pytest.mark.parametrize("n", range(0, 30))
@pytest.mark.parametrize("size", [1, 3, 4, 8])
@pytest.mark.parametrize("workers", [1, 2, 5, 64])
def test_batches_cover_in_order_bounded_and_spread(n: int, size: int, workers: int) -> None:
    items = list(range(100, 100 + n))
    batches = split_evenly(items, size, workers)
    assert [i for batch in batches for i in batch] == items
    assert all(1 <= len(batch) <= size for batch in batches)
    lengths = {len(batch) for batch in batches}
    assert not lengths or max(lengths) - min(lengths) <= 1
    # as few batches as the size allows, but one per worker while there are robots for it
    assert len(batches) == min(n, max(-(-n // size), workers))


def test_few_new_robots_are_spread_over_the_workers() -> None:
    """5 new genomes, batches of 4, 2 workers: 3 + 2, not 4 + 1; 3 new on 2 workers: 2 + 1."""
    assert split_evenly([0, 1, 2, 3, 4], 4, 2) == [[0, 1, 2], [3, 4]]
    assert split_evenly([7, 8, 9], 4, 2) == [[7, 8], [9]]
    assert split_evenly(list(range(9)), 4, 1) == [[0, 1, 2], [3, 4, 5], [6, 7, 8]]
