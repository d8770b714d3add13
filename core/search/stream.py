"""The one step of every strategy: births go out as worker slots free and are told in birth
order, so no core waits at a barrier that the strategy does not have.

`Stepper.step` runs it; the strategy gives the row's `Cohort` (`softevo.core.search.cohort`). A
step ends with one curve row (a generation, or `population` births), but births in flight at its
end stay in flight (`Flights`, which outlives the step) and the next step takes their results.
Births whose genome an earlier birth had are not simulated again. Robots waiting to go out are
sent together, up to the batch size, whenever a slot frees: small robots share a kernel call
and a round trip. At a step's end the next row's births (a generation bred at once) are handed
to the hooks, so the commit of this row keeps them.
"""

from __future__ import annotations

import math
import queue
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from softevo.core.evaluator import (
    CHECK_SECONDS,
    BatchResult,
    Evaluator,
    batch_count,
    hand_over,
    names_digest,
)
from softevo.core.search.cohort import Birth, Cohort
from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.step import Hooks, Step
from softevo.core.search.strategy import Strategy


class Stepper(Protocol):
    """What the step reads of the run's `generation.Stepper`."""

    @property
    def algorithm(self) -> Strategy: ...
    def robot_file(self, individual: Individual) -> dict[str, Any]: ...
    def flights(self, evaluator: Evaluator, alarm: threading.Event | None) -> Flights: ...
    def cohort(self, state: StrategyState, known: dict[str, float]) -> Cohort: ...


#: What a batch thread hands back: the births it held, its result or what it raised.
Landing = tuple[list[Birth], BatchResult | None, BaseException | None]


@dataclass
class Flights:
    """The batches of one run in flight, across steps: handed to the evaluator by the shared
    batch threads, their landings queued for whichever step is running."""

    evaluator: Evaluator
    batch_size: int
    in_flight: int
    alarm: threading.Event  # set when a batch lands (the hooks' alarm, which a stop rings too)
    out: set[str] = field(default_factory=set)  # genome hashes sent and not landed
    batches: int = 0  # batches sent and not landed
    kept: int = -1  # the last birth (number) handed to the hooks
    #: Whether each landing wakes the step (it may send or tell on it), or only the last one in
    #: flight: a wake-up costs the step's process more CPU than taking batches in
    wake_each: bool = True
    landings: queue.SimpleQueue[Landing] = field(default_factory=queue.SimpleQueue)

    def free(self, waiting: int, growing: bool) -> bool:
        """Whether a batch of the `waiting` robots may go out now: while a worker is idle, any
        batch; a second one per worker (there when the first lands) only a full one while the
        row is `growing` (births to come may fill it), so robots wait to share a call rather
        than each pay one; never more than `in_flight`."""
        workers = self.evaluator.capacity()
        if self.batches >= min(self.in_flight, 2 * workers):
            return False
        return self.batches < workers or waiting >= self.batch_size or not growing

    def portion(self, waiting: int) -> int:
        """Robots for the next batch of a row asked at once: up to a batch, but the `waiting`
        ones shared evenly among the idle workers as `split_evenly` cuts them (5 on 2: 3 and 2,
        not 4 and 1), so none idles while another runs a long batch before the row's end."""
        idle = max(1, self.evaluator.capacity() - self.batches)
        return math.ceil(waiting / batch_count(waiting, self.batch_size, idle))

    def send(self, births: list[Birth], files: list[dict[str, Any]], key: str) -> None:
        names = [birth.individual.genome.hash for birth in births]
        self.out.update(names)
        self.batches += 1
        hand_over(self._evaluate, births, files, f"{key}-b{births[0].number}-{names_digest(names)}")

    def _evaluate(self, births: list[Birth], files: list[dict[str, Any]], key: str) -> None:
        try:
            self.landings.put((births, self.evaluator.evaluate_batch(files, key), None))
        except BaseException as error:  # the step raises it, at once
            self.landings.put((births, None, error))
            self.alarm.set()
            return
        # or the last in flight (`batches` is the step's; it changes only while the step is
        # awake, and then it takes what landed before it sleeps again)
        if self.wake_each or self.landings.qsize() >= self.batches:
            self.alarm.set()

    def take(self, wait: float) -> list[Landing]:
        """What landed, waiting up to `wait` s (or until the alarm rings) for the first."""
        if self.landings.empty():
            self.alarm.wait(wait)
        self.alarm.clear()
        landed = []
        while not self.landings.empty():
            births, result, error = self.landings.get_nowait()
            self.batches -= 1
            self.out.difference_update(birth.individual.genome.hash for birth in births)
            landed.append((births, result, error))
        return landed


@dataclass
class _Row:
    """The step's bookkeeping: the births waiting to go out, the alarm that wakes it."""

    stepper: Stepper
    cohort: Cohort
    flights: Flights
    cache: dict[str, float]
    measures: dict[str, dict[str, float]]
    hooks: Hooks
    key: str
    waiting: deque[Birth] = field(default_factory=deque)

    def keep(self, births: list[Birth]) -> None:
        """Births: kept by the hooks unless they were (the hooks may know their fitness, after
        a takeover), and queued to go out unless an earlier birth has their genome."""
        generations = self.stepper.algorithm.config.generations
        births = [birth for birth in births if birth.row < generations]  # past the end: not sent
        kept, fresh = self.flights.kept, [b for b in births if b.number > self.flights.kept]
        self.flights.kept = max(kept, fresh[-1].number) if fresh else kept
        for generation, members in _by_row(fresh).items():
            individuals = {index: fresh[p].individual for index, p in members.items()}
            known, records = self.hooks.births(generation, individuals)
            for index, value in known.items():
                genome_hash = individuals[index].genome.hash
                self.cache.setdefault(genome_hash, value)
                self.measures.setdefault(genome_hash, records.get(index, {}))
        # a saved birth waits too if its genome is unknown (a cache cleared since it was
        # bred): `send` drops it while its twin is known or in flight
        cache = self.cache
        self.waiting.extend(
            b for b in births if not b.saved or b.individual.genome.hash not in cache
        )

    def send(self) -> None:
        """Fill free slots with the waiting births (up to a batch each)."""
        flights = self.flights
        growing = self.cohort.growing
        while self.waiting and flights.free(len(self.waiting), growing):
            births: list[Birth] = []
            # a row asked at once is shared among the idle workers, so none waits at its end
            size = flights.batch_size if growing else flights.portion(len(self.waiting))
            while self.waiting and len(births) < size:
                birth = self.waiting.popleft()
                genome_hash = birth.individual.genome.hash
                if genome_hash not in self.cache and genome_hash not in flights.out:
                    births.append(birth)
            if births:
                files = [self.stepper.robot_file(birth.individual) for birth in births]
                flights.send(births, files, self.key)

    def landed(self, births: list[Birth], result: BatchResult) -> None:
        """A batch's results: cached by genome, and handed to the hooks by row."""
        records = result.records()
        for birth, value, record in zip(births, result.fitness.tolist(), records, strict=True):
            self.cache[birth.individual.genome.hash] = value
            self.measures[birth.individual.genome.hash] = record
        for generation, members in _by_row(births).items():
            positions = list(members.values())
            part = BatchResult(
                result.fitness[positions],
                result.worker,
                result.seconds * len(positions) / len(births),
                [records[p] for p in positions],
            )
            self.hooks.batch(generation, list(members), part)


def stream_step(
    stepper: Stepper,
    state: StrategyState,
    cache: dict[str, float],
    evaluator: Evaluator,
    hooks: Hooks,
    key: str,
    measures: dict[str, dict[str, float]],
) -> Step:
    """Tell one row's births, in birth order (see the module)."""
    started = time.perf_counter()
    cohort = stepper.cohort(state, cache)
    flights = stepper.flights(evaluator, hooks.alarm)
    row = _Row(stepper, cohort, flights, cache, measures, hooks, key)
    row.keep(list(cohort.window))
    try:
        while not cohort.row_done:
            _tell_known(row)
            if cohort.row_done:
                break
            row.send()
            due = hooks.check()
            late = due is not None and time.monotonic() >= due
            if late:  # a write is due: what waits for it goes now, and each landing at once
                hooks.flush()
            # nothing to send and no birth to come: only the row's last landing (or `due`) counts
            flights.wake_each = late or cohort.growing or bool(row.waiting)
            wait = CHECK_SECONDS if due is None or late else due - time.monotonic()
            for births, result, error in flights.take(min(CHECK_SECONDS, max(0.0, wait))):
                if error is not None:
                    raise error
                assert result is not None
                row.landed(births, result)
    except BaseException:
        for births, result, _error in flights.take(0.0):  # what landed is kept
            if result is not None:
                row.landed(births, result)
        raise
    following, stats = cohort.finish()
    told = list(cohort.row)  # before the next row goes on (in this cohort, for steady-state)
    if not stepper.algorithm.done(following):  # the next row's births, kept with this one
        row.keep(list(stepper.cohort(following, cache).window))
    fitness = np.array([item[1] for item in told], dtype=np.float64)
    evaluated = frozenset(i for i, item in enumerate(told) if not item[3])
    individuals, records = [item[0] for item in told], [item[2] for item in told]
    seconds = time.perf_counter() - started
    return Step(individuals, fitness, records, evaluated, stats, following, seconds)


def _by_row(births: list[Birth]) -> dict[int, dict[int, int]]:
    """Births by the curve row (generation) they belong to: index in it -> position in `births`."""
    rows: dict[int, dict[int, int]] = {}
    for position, birth in enumerate(births):
        rows.setdefault(birth.row, {})[birth.index] = position
    return rows


def _tell_known(row: _Row) -> None:
    """Tell every birth, oldest first, whose fitness is known; each may breed another. The new
    births are kept together (one call of the hooks, not one a birth), but before the oldest
    in flight is one of them (a window of 1): the hooks may know its fitness, after a takeover."""
    cohort, cache = row.cohort, row.cache
    bred: list[Birth] = []
    while not cohort.row_done and cohort.window:
        if bred and cohort.window[0].number >= bred[0].number:
            row.keep(bred)
            bred = []
        genome_hash = cohort.window[0].individual.genome.hash
        if genome_hash not in cache:
            break
        born = cohort.tell(cache[genome_hash], row.measures.get(genome_hash, {}), cache)
        if born is not None:
            bred.append(born)
    if bred:
        row.keep(bred)
