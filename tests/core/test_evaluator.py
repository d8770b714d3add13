"""How the step cuts a row's new robots into batches on idle workers (`split_evenly`, whose
sizes `Flights.portion` gives batch after batch)."""

from __future__ import annotations

import threading

import pytest

from softevo.core.evaluator import BatchResult, Evaluator, split_evenly
from softevo.core.search.stream import Flights


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


class Workers(Evaluator):
    """Only its number of workers is read."""

    def __init__(self, workers: int) -> None:
        self.workers = workers

    def evaluate_batch(self, robot_files: object, key: str | None = None) -> BatchResult:
        raise AssertionError("nothing is evaluated")

    def capacity(self) -> int:
        return self.workers

    def close(self) -> None:
        pass


@pytest.mark.parametrize("size", [1, 3, 4, 8])
@pytest.mark.parametrize("workers", [1, 2, 5, 64])
def test_the_step_cuts_a_row_asked_at_once_as_split_evenly_does(size: int, workers: int) -> None:
    for n in range(1, 40):
        flights, waiting, sizes = Flights(Workers(workers), size, 64, threading.Event()), n, []
        while waiting:
            sizes.append(flights.portion(waiting))
            waiting -= sizes[-1]
            flights.batches += 1  # the batch went out: one worker fewer idle
        evenly = [len(batch) for batch in split_evenly(range(n), size, workers)]
        assert sorted(sizes) == sorted(evenly), n
