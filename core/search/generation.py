"""One generation step, the only one: ask -> split the generation into genomes whose fitness is
known and new ones -> evaluate the new ones in batches, several in flight -> tell.

The library (`softevo.core.evolution`) and the service's driver (for the service and for
`softevo run`) both run it; the driver adds persistence through `Hooks`, never a second copy of
the loop, so an algorithm plugs in once and runs everywhere. Counting is the same for both: a
genome seen in an earlier generation of the run is not simulated again (`saved`); within a
generation, each distinct new genome is simulated once (`evaluations`), and one whose fitness a
hook already holds (saved before a crash) is counted as evaluated but not simulated again. A
streaming strategy (`steady-state`) is told one birth at a time instead, its births streamed to
the evaluator (`softevo.core.search.stream`); its step still ends with one curve row, through
the same hooks.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from softevo.core.evaluator import BatchResult, Evaluator, evaluate_in_batches
from softevo.core.limits import BATCH_SIZE, IN_FLIGHT, SMALL_BATCH, SMALL_POINTS
from softevo.core.robots.encodings import Encoding
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.robots.settings import SimSettings
from softevo.core.search.configured import Individual, Strategy, StrategyState
from softevo.core.search.step import Hooks, Step
from softevo.core.search.stream import Flights, stream_step
from softevo.core.search.vectors import needs_energy


@dataclass(frozen=True)
class Stepper:
    """What runs the generation step for one run (named apart from the database's engine and
    the workers' physics fingerprint): an algorithm with the run's encoding and simulation
    settings, and how it evaluates:
    batches of at most `batch_size` robots, at most `in_flight` of them at once, each robot's
    fitness measured by `objective`."""

    algorithm: Strategy
    sim: SimSettings
    batch_size: int = BATCH_SIZE
    in_flight: int = IN_FLIGHT
    objective: str = "speed"
    max_simulations: int | None = None

    def done(self, state: StrategyState, simulations: int) -> bool:
        """Whether the run ends at `state`: its strategy is done, or the `simulations` of its
        rows so far reach the run's `max_simulations` (rows are the same for any number of
        workers, so is where the run ends)."""
        budget = self.max_simulations
        return self.algorithm.done(state) or (budget is not None and simulations >= budget)

    @property
    def encoding(self) -> Encoding:
        return self.algorithm.encoding

    @cached_property
    def sim_json(self) -> dict[str, Any]:
        """The run's simulation settings as every robot file holds them, dumped once."""
        return self.sim.model_dump()

    def robot_file(self, individual: Individual) -> dict[str, Any]:
        """The individual's robot file; one measured by another objective than `speed` says so
        (a `speed` file stays as it always was, so are its batch keys), and one whose run's
        objectives need the actuators' work asks for it."""
        document = robot_to_json(self.encoding.to_robot(individual.genome, self.sim), self.sim_json)
        if self.objective != "speed":
            document["objective"] = self.objective
        if self.energy:
            document["energy"] = True
        return document

    @cached_property
    def energy(self) -> bool:
        """Whether the run's `objectives` read the actuators' work (its robot files ask for it;
        a run without them sends the files it always did)."""
        return needs_energy(self.algorithm.config.objectives)

    @cached_property
    def stream_batch(self) -> int:
        """Robots per call of a streaming strategy: `batch_size`, or at least `SMALL_BATCH` for
        robots of a box of at most `SMALL_POINTS` lattice points, whose calls would otherwise
        cost more than their simulations (which are the same bits in any batch)."""
        shape = getattr(self.encoding, "shape", None)
        points = math.prod(side + 1 for side in shape) if shape else SMALL_POINTS + 1
        return max(self.batch_size, SMALL_BATCH) if points <= SMALL_POINTS else self.batch_size

    def flights(self, evaluator: Evaluator, alarm: threading.Event | None) -> Flights:
        """The run's batches in flight, kept across the steps of a streaming strategy."""
        flights = self.__dict__.get("_flights")
        if flights is None or flights.evaluator is not evaluator:
            alarm = alarm or threading.Event()
            flights = Flights(evaluator, self.stream_batch, self.in_flight, alarm)
            self.__dict__["_flights"] = flights
        return flights

    def step(
        self,
        state: StrategyState,
        cache: dict[str, float],
        evaluator: Evaluator,
        hooks: Hooks | None = None,
        key: str = "local",
        measures: dict[str, dict[str, float]] | None = None,
    ) -> Step:
        """Run generation `state.generation`. `cache` (genome hash -> fitness of the run's
        earlier generations) gains this generation's new genomes, and so does `measures`
        (genome hash -> record of measures, beside it); `key` prefixes batch keys."""
        hooks = hooks or Hooks()
        measures = {} if measures is None else measures
        if self.algorithm.streaming:
            return stream_step(self, state, cache, evaluator, hooks, key, measures)
        started = time.perf_counter()
        generation = state.generation
        individuals = self.algorithm.ask(state)
        known, known_measures = hooks.individuals(generation, individuals)
        hashes = [individual.genome.hash for individual in individuals]
        first = _first_new(hashes, cache)
        todo = [index for index in first.values() if index not in known]
        fitness = {index: known[index] for index in first.values() if index in known}
        records = {index: known_measures.get(index, {}) for index in fitness}
        if todo:
            batch = _Batch(generation, key, todo, [hashes[i] for i in todo])
            values = self._evaluate(
                batch, [individuals[i] for i in todo], evaluator, hooks, records
            )
            fitness.update(zip(todo, values.tolist(), strict=True))
        cache.update({hashes[index]: value for index, value in fitness.items()})
        measures.update({hashes[index]: record for index, record in records.items()})
        values = np.array([cache[h] for h in hashes], dtype=np.float64)
        found = [measures.get(h, {}) for h in hashes]
        evaluations = len(first)
        following, stats = self.algorithm.tell(
            state,
            individuals,
            values,
            measures=found,
            evaluations=evaluations,
            saved=len(individuals) - evaluations,
        )
        seconds = time.perf_counter() - started
        return Step(
            individuals, values, found, frozenset(first.values()), stats, following, seconds
        )

    def _evaluate(
        self,
        batch: _Batch,
        individuals: list[Individual],
        evaluator: Evaluator,
        hooks: Hooks,
        records: dict[int, Any],
    ) -> np.ndarray:
        """Simulate the generation's new genomes (`batch.todo`, by index), in batches whose
        records and fitness the hooks see as they land."""
        files = [self.robot_file(individual) for individual in individuals]

        def landed(positions: list[int], result: BatchResult) -> None:
            indices = [batch.todo[p] for p in positions]
            records.update(zip(indices, result.records(), strict=True))
            hooks.batch(batch.generation, indices, result)

        return evaluate_in_batches(
            evaluator,
            files,
            f"{batch.key}-gen{batch.generation}",
            batch_size=self.batch_size,
            in_flight=self.in_flight,
            check=hooks.check,
            on_batch=landed,
            alarm=hooks.alarm,
            names=batch.names,  # a robot file is its genome's, in one run
        )


def _first_new(hashes: list[str], cache: dict[str, float]) -> dict[str, int]:
    """Each genome the cache does not know, by hash, at the index of its first copy."""
    first: dict[str, int] = {}
    for index, genome_hash in enumerate(hashes):
        if genome_hash not in cache and genome_hash not in first:
            first[genome_hash] = index
    return first


@dataclass(frozen=True)
class _Batch:
    """A generation's genomes to simulate: their indices and hashes, and the batches' key."""

    generation: int
    key: str
    todo: list[int]
    names: list[str]
