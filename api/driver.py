"""One run driven by the coordinator: the step of `softevo.core.search.generation` with
persistence around it (`RunDriver`, the step's hooks). Births are written with the next write
(a row's commit keeps the next row's, so a generation after the first is stored before it is
evaluated), batches' fitness is saved as it lands (a batch that lands within `save_seconds` of
the run's last write waits for the next one), and each row is committed in one transaction.
The strategy state of the last committed row is all a successor needs (see
`softevo.api.coordinator`)."""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from sqlalchemy.exc import InterfaceError, InternalError, OperationalError

from softevo.api import store
from softevo.api.db import Database, EncodedJSON
from softevo.api.faults import Faults
from softevo.api.store.driving import (
    GenerationCommit,
    GenerationMismatchError,
    Landed,
    Lease,
    LeaseLostError,
    Member,
)
from softevo.core.config import RunConfig
from softevo.core.evaluator import BatchResult, Evaluator
from softevo.core.search.configured import Individual, StrategyState, make_strategy
from softevo.core.search.generation import Hooks, Step, Stepper
from softevo.core.search.state import parents_text
from softevo.core.status import RunStatus

log = logging.getLogger("softevo.coordinator")


class Stop(Exception):  # noqa: N818 - a signal, not an error
    """The driver must stop: shutdown, cancellation or a lost lease."""


@dataclass(frozen=True)
class Driving:
    """What every driver of one coordinator shares: where it stores, how it evaluates."""

    db: Database
    evaluator: Evaluator
    lease: Lease
    batch_size: int
    in_flight: int
    save_seconds: float  # fitness landing within this of the run's last write waits for the next
    stopping: threading.Event
    faults: Faults


class RunDriver(Hooks):
    """Drives one run while its coordinator holds the lease; the step's persistence hooks."""

    alarm: threading.Event  # always set up here (Hooks allows none)

    def __init__(self, driving: Driving, run_id: int) -> None:
        self.driving = driving
        self.db = driving.db
        self.run_id = run_id
        self.key = f"run{run_id}"  # every batch key of the run starts with it and a dash
        self.abort, self.alarm = threading.Event(), threading.Event()  # alarm: wakes the step
        self.reason = ""
        self.landed: list[Landed] = []  # batches' fitness not written yet
        self.written = time.monotonic()  # when this driver last wrote
        self.generation: int | None = None  # the generation being evaluated
        self.members: list[Member] = []  # births asked and not written yet
        self.stored: dict[tuple[int, int], Any] | None = None  # its births found at takeover

    # -- control -------------------------------------------------------------------------------

    def stop(self, reason: str) -> None:
        self.reason = reason
        self.abort.set()
        self.alarm.set()

    def check(self) -> float:
        """Called while batches run (at once when `alarm` rings): stops the step, or says when
        the run's next write is due; a batch landing from then on is handed to `batch` and
        written at once (so no fitness waits longer than `save_seconds`, however slow the
        rest)."""
        if self.abort.is_set():
            raise Stop(self.reason)
        if self.driving.stopping.is_set():
            raise Stop("shutdown")
        return self.written + self.driving.save_seconds

    # -- the hooks of the generation step -------------------------------------------------------

    def batch(self, generation: int, indices: list[int], result: BatchResult) -> None:
        fitness = dict(zip(indices, result.fitness.tolist(), strict=True))
        measures = dict(zip(indices, result.records(), strict=True))
        seconds_each = result.seconds / max(1, len(indices))
        self.landed.append(Landed(fitness, result.worker, seconds_each, measures, generation))
        if self._due():
            self._save(generation)

    def births(
        self, generation: int, individuals: dict[int, Individual]
    ) -> tuple[dict[int, float], dict[int, dict[str, float]]]:
        """Each birth (the step hands it over once) is written with the next write (a row's
        commit keeps the next row's); the first call (after a takeover) finds those a
        predecessor kept, and what it evaluated."""
        if self.stored is None:
            self.stored = store.births.stored_births(self.db, self.run_id, generation)
        known: dict[int, float] = {}
        records: dict[int, dict[str, float]] = {}
        for index, individual in individuals.items():
            found = self.stored.pop((generation, index), None)
            if found is None:
                self.members.append((generation, index, members([individual])[0]))
            elif found[0] != individual.genome.hash:
                raise GenerationMismatchError(
                    f"birth {index} of generation {generation} in the database differs from the "
                    "one bred from the run's seed; refusing to mix them"
                )
            elif found[1] is not None:
                known[index], records[index] = found[1], found[2]
        return known, records

    def flush(self) -> None:
        if (self.landed or self.members) and self.generation is not None:
            self._save(self.generation)

    def _due(self) -> bool:
        return time.monotonic() - self.written >= self.driving.save_seconds

    def _save(self, generation: int) -> None:
        """Write the fitness that landed and waits (one statement for all its batches)."""
        landed, self.landed = self.landed, []
        births, self.members = self.members, []
        self.written = time.monotonic()
        self._fenced(store.driving.save_fitness, generation, landed, births)

    def _fenced(self, write: Callable[..., Any], *args: Any) -> Any:
        """`write(db, run, lease, *args)`; a lost lease stops the driver."""
        try:
            return write(self.db, self.run_id, self.driving.lease, *args)
        except LeaseLostError as lost:
            self.stop(str(lost))
            raise Stop(self.reason) from None

    # -- the loop ------------------------------------------------------------------------------

    def run(self) -> None:
        try:
            self.drive()
        except Stop as stop:
            log.info("run %s: driver stopped (%s)", self.run_id, stop)
            self._drop_if_cancelled()
            self._save_on_stop()
        except (OperationalError, InterfaceError, InternalError) as error:  # the database: said
            self.driving.faults.record(error, f"run {self.run_id}")
        except Exception as error:  # any bug or evaluator failure fails the run
            log.exception("run %s failed", self.run_id)
            try:
                store.driving.fail(
                    self.db,
                    self.run_id,
                    self.driving.lease.owner,
                    f"{type(error).__name__}: {error}",
                )
            except Exception:  # the database itself is away; the lease will expire
                log.exception("run %s: could not record the failure", self.run_id)

    def _drop_if_cancelled(self) -> None:
        """Cancelled here or through another API process (then the lease fence stopped us):
        the run's batches still out are given up, not finished."""
        try:
            cancelled = self.reason == "cancelled" or (
                store.get_run(self.db, self.run_id).status == RunStatus.CANCELLED
            )
            if cancelled:
                self.driving.evaluator.drop(f"{self.key}-")
        except Exception:  # a backend that cannot drop: its batches finish, nothing is lost
            log.exception("run %s: could not give up the cancelled run's batches", self.run_id)

    def _save_on_stop(self) -> None:
        """Stopped mid-generation (shutdown, cancel, lost lease): keep what landed if the lease
        still allows it, so a successor need not evaluate it again."""
        if not (self.landed or self.members) or self.generation is None:
            return
        try:
            self._save(self.generation)
        except Stop:  # the lease is gone (cancelled, taken over): the write was refused
            pass
        except (OperationalError, InterfaceError, InternalError) as error:
            self.driving.faults.record(error, f"run {self.run_id}")

    def drive(self) -> None:
        """Run the remaining generations; errors raise (`run` records them on the run)."""
        stored_config, stored_state = store.driving.load(self.db, self.run_id)
        config = RunConfig.model_validate(stored_config)
        algorithm = make_strategy(config.strategy_settings(), config.make_encoding())
        driving = self.driving
        stepper = Stepper(
            algorithm,
            config.sim,
            driving.batch_size,
            driving.in_flight,
            config.objective,
            config.max_simulations,
        )
        state = (
            StrategyState.from_json(stored_state) if stored_state else algorithm.start(config.seed)
        )
        cache, measures = store.driving.known_fitness(self.db, self.run_id, state.generation)
        simulations = store.get_run(self.db, self.run_id).evaluations  # of the committed rows
        while not stepper.done(state, simulations):
            self.check()
            self.generation = state.generation
            step = stepper.step(state, cache, self.driving.evaluator, self, self.key, measures)
            state, simulations = step.state, simulations + step.stats.evaluations
            self._commit(step, stepper.done(state, simulations))

    def _commit(self, step: Step, done: bool) -> None:
        """The row's fitness, statistics, strategy state and counters and the births asked
        since the last write (the next row's, unless the run is `done`), all or nothing."""
        generation = step.stats.generation
        births = [item for item in self.members if not done or item[0] <= generation]
        best, archive = step.state.best, step.state.archive
        commit = GenerationCommit(
            stats=step.stats.to_json(),
            # the curve is in `generations`, the archive in a column of its own
            state=EncodedJSON(step.state.to_text(history=False, archive=False)),
            archive=None if archive is None else EncodedJSON(archive.to_text()),
            cached={
                index: value
                for index, value in enumerate(step.fitness.tolist())
                if index not in step.evaluated
            },
            cached_measures={
                index: record
                for index, record in enumerate(step.measures)
                if index not in step.evaluated
            },
            landed=self.landed,
            best=None if best is None else (best[1], best[2]),
            done=done,
            seconds=step.seconds,
            members=births,
        )
        self.landed, self.members, self.written = [], [], time.monotonic()
        self._fenced(store.driving.commit_generation, commit)
        self.driving.faults.clear()  # a generation committed: the database takes writes
        self.committed(step)

    def committed(self, step: Step) -> None:
        """After each generation's commit: nothing for the service (`softevo run` shows its
        progress and writes its files)."""


def members(individuals: list[Individual]) -> list[dict[str, Any]]:
    """Individuals as the store keeps them."""
    return [
        {
            "genome": EncodedJSON(item.genome.canonical),
            "genome_hash": item.genome.hash,
            "operator": item.operator,
            "parents": EncodedJSON(parents_text(item.parents)),
        }
        for item in individuals
    ]
