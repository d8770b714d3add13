"""What a generation step gives back (`Step`) and what happens around it (`Hooks`): the
contract between the step (`softevo.core.search.stream`) and whoever runs it (the
library, the service's driver), in a module of its own so both sides import it and not each
other."""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np

from softevo.core.evaluator import BatchResult
from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.stats import GenerationStats


class Hooks:
    """What happens around a step (persistence, cancellation); by default nothing."""

    #: Set by another thread to have `check` called at once (a stop); without one, `check` is
    #: called at least every `evaluator.CHECK_SECONDS` while batches run.
    alarm: threading.Event | None = None

    def check(self) -> float | None:
        """Raise to stop the step (cancelled, lease lost, shutdown); called while batches run.
        Returns the `time.monotonic()` from which a batch that lands goes to `batch` at once
        (None: at the step's end is soon enough)."""
        return None

    def batch(self, generation: int, indices: list[int], result: BatchResult) -> None:
        """One batch's fitness and measures landed (for `indices` of row `generation`, in
        order)."""

    def births(
        self, generation: int, individuals: dict[int, Individual]
    ) -> tuple[dict[int, float], dict[int, dict[str, float]]]:
        """The strategy asked these members of row `generation` (by index): keep them; return
        fitness already known for some of them (by index; NaN = failed), which are then not
        simulated again, and the records of measures known for them (a member without one gets
        an empty record)."""
        return {}, {}

    def flush(self) -> None:
        """The step's `check` said a write was due and no batch landed since: write what
        waits."""


@dataclass(frozen=True)
class Step:
    """What one step did (one curve row), and the state after it."""

    individuals: list[Individual]
    fitness: np.ndarray  # of every individual, in order (NaN = failed)
    measures: list[dict[str, float]]  # of every individual, in order (empty: none known)
    evaluated: frozenset[int]  # indices whose fitness came from this step (not from the cache)
    stats: GenerationStats
    state: StrategyState  # the state after the generation was told
    seconds: float
