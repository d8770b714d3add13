"""What runs a run's steps (`Stepper`): the one step of every strategy (`stream.stream_step`),
its evaluation settings, robot files and batches in flight.

The library (`softevo.core.evolution`) and the service's driver (for the service and for
`softevo run`) both run it; the driver adds persistence through `Hooks`, never a second copy of
the loop, so an algorithm plugs in once and runs everywhere. Counting is the same for both: a
genome seen in an earlier birth of the run is not simulated again (`saved`); each distinct new
genome is simulated once (`evaluations`), and one whose fitness a hook already holds (saved
before a crash) is counted as evaluated but not simulated again.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from softevo.core.evaluator import Evaluator
from softevo.core.limits import BATCH_SIZE, IN_FLIGHT, SMALL_BATCH, SMALL_POINTS
from softevo.core.robots.encodings import Encoding
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.robots.settings import SimSettings
from softevo.core.search.cohort import Cohort
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
    def robots_per_call(self) -> int:
        """Robots per call: `batch_size`, or at least `SMALL_BATCH` for
        robots of a box of at most `SMALL_POINTS` lattice points, whose calls would otherwise
        cost more than their simulations (which are the same bits in any batch)."""
        shape = getattr(self.encoding, "shape", None)
        points = math.prod(side + 1 for side in shape) if shape else SMALL_POINTS + 1
        return max(self.batch_size, SMALL_BATCH) if points <= SMALL_POINTS else self.batch_size

    def flights(self, evaluator: Evaluator, alarm: threading.Event | None) -> Flights:
        """The run's batches in flight, kept across its steps."""
        flights = self.__dict__.get("_flights")
        if flights is None or flights.evaluator is not evaluator:
            alarm = alarm or threading.Event()
            flights = Flights(evaluator, self.robots_per_call, self.in_flight, alarm)
            self.__dict__["_flights"] = flights
        return flights

    def cohort(self, state: StrategyState, known: dict[str, float]) -> Cohort:
        """Row `state.generation`'s cohort: the last one, if it goes on from `state` (the
        step's end made it, or a steady-state row goes on in memory), else the strategy's."""
        last = self.__dict__.get("_cohort")
        cohort = None if last is None else last.go_on(state)
        if cohort is None:
            cohort = self.algorithm.cohort(state, known)
        self.__dict__["_cohort"] = cohort
        return cohort

    def step(
        self,
        state: StrategyState,
        cache: dict[str, float],
        evaluator: Evaluator,
        hooks: Hooks | None = None,
        key: str = "local",
        measures: dict[str, dict[str, float]] | None = None,
    ) -> Step:
        """Run row `state.generation`. `cache` (genome hash -> fitness of the run's earlier
        births) gains this row's new genomes, and so does `measures` (genome hash -> record of
        measures, beside it); `key` prefixes batch keys."""
        hooks = hooks or Hooks()
        measures = {} if measures is None else measures
        return stream_step(self, state, cache, evaluator, hooks, key, measures)
