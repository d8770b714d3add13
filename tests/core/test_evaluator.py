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


def test_a_stopped_evaluation_hands_over_no_more_batches() -> None:
    """Cancel stops the compute: once `check` raises, the batches not yet handed to the
    evaluator are dropped; at most two per worker were ever out."""
    import threading

    import numpy as np
    import pytest

    from softevo.core.evaluator import BatchResult, Evaluator, evaluate_in_batches

    release, started = threading.Event(), []

    class Slow(Evaluator):
        def evaluate_batch(self, robot_files, key=None):  # type: ignore[no-untyped-def]
            started.append(key)
            release.wait(10)
            return BatchResult(np.zeros(len(robot_files)), "slow", 0.0)

        def capacity(self) -> int:
            return 2

        def close(self) -> None:
            pass

    class StoppedError(Exception):
        pass

    def check() -> None:
        if len(started) >= 4:
            raise StoppedError

    files = [{"robot": i} for i in range(80)]  # 20 batches of 4
    with pytest.raises(StoppedError):
        evaluate_in_batches(Slow(), files, batch_size=4, check=check)
    release.set()
    assert len(started) == 4  # two per worker out; the other 16 never handed over
