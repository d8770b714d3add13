"""What a generation step gives back (`Step`) and what happens around it (`Hooks`): the
contract between the step (`softevo.core.search.generation`, `stream`) and whoever runs it (the
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

    def individuals(
        self, generation: int, individuals: list[Individual]
    ) -> tuple[dict[int, float], dict[int, dict[str, float]]]:
        """The generation is about to be evaluated: keep it; return fitness already known for
        some of its members (by index; NaN = failed), which are then not simulated again, and
        the records of measures known for them (a member without one gets an empty record)."""
        return {}, {}

    def batch(self, generation: int, indices: list[int], result: BatchResult) -> None:
        """One batch's fitness and measures landed (for `indices` of the generation, in
        order)."""

    def births(
        self, generation: int, individuals: dict[int, Individual]
    ) -> tuple[dict[int, float], dict[int, dict[str, float]]]:
        """A streaming strategy bred these members of row `generation` (by index): keep them;
        return what is known of them, as `individuals` does."""
        return {}, {}

    def flush(self) -> None:
        """A streaming step's `check` said a write was due and no batch landed since: write
        what waits."""


@dataclass(frozen=True)
class Step:
    """What one generation step did, and the state after it."""

    individuals: list[Individual]
    fitness: np.ndarray  # of every individual, in order (NaN = failed)
    measures: list[dict[str, float]]  # of every individual, in order (empty: none known)
    evaluated: frozenset[int]  # indices whose fitness came from this step (not from the cache)
    stats: GenerationStats
    state: StrategyState  # the state after the generation was told
    seconds: float
