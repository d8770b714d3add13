"""The coordinator: drives runs generation by generation inside the API process.

For each run it owns (see `store.leases`) it runs the one generation step of
`softevo.core.generation` with persistence around it (`RunDriver`): the generation's individuals
are kept before anything is evaluated, batches' fitness is saved as it lands (a batch that lands
within `save_seconds` of the run's last write waits for the next one, so a generation of quick
batches costs one transaction, not one per batch), and the generation (its remaining fitness,
statistics, the GA state, the run's counters, and the next generation's members, bred at once)
is committed in one transaction. The GA state stored with the last committed generation is all a
successor needs: generation g is bred from (seed, g) and generation g-1 alone, so a run taken over
after a crash regenerates the same individuals, re-evaluates only those without fitness and ends
with the same learning curve as an undisturbed run.
"""

from __future__ import annotations

import logging
import os
import socket
import threading
import time
import uuid
from dataclasses import dataclass, replace
from typing import Any

from sqlalchemy.exc import InterfaceError, InternalError, OperationalError

from softevo.api import store
from softevo.api.db import Database, EncodedJSON
from softevo.api.faults import Faults
from softevo.api.store.driving import GenerationCommit, Landed, Lease, LeaseLostError
from softevo.core.config import RunConfig
from softevo.core.evaluator import BatchResult, Evaluator
from softevo.core.ga.algorithm import GAState, Individual, make_strategy
from softevo.core.ga.state import parents_text
from softevo.core.generation import Engine, Hooks, Step
from softevo.core.limits import BATCH_SIZE, IN_FLIGHT, SAVE_SECONDS
from softevo.core.status import RunStatus

log = logging.getLogger("softevo.coordinator")

#: While its looks for runs to start find none, the scheduler doubles its pause up to this many
#: `poll_seconds` (never past a heartbeat): an idle service looks every few seconds, not twice a
#: second. A run queued through this process, or a driver ending, wakes it at once.
QUIET_BACKOFF = 8


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

    def __init__(self, driving: Driving, run_id: int) -> None:
        self.driving = driving
        self.db = driving.db
        self.run_id = run_id
        self.key = f"run{run_id}"  # every batch key of the run starts with it and a dash
        self.abort, self.alarm = threading.Event(), threading.Event()  # alarm: wakes the step
        self.reason = ""
        self.landed: list[Landed] = []  # batches' fitness not written yet
        self.kept: int | None = None  # the generation this driver's last commit kept
        self.written = time.monotonic()  # when this driver last wrote
        self.generation: int | None = None  # the generation being evaluated

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

    def individuals(
        self, generation: int, individuals: list[Individual]
    ) -> tuple[dict[int, float], dict[int, dict[str, float]]]:
        if generation == self.kept:  # kept by this driver's last commit, nothing evaluated since
            return {}, {}
        self.written = time.monotonic()
        return self._fenced(store.driving.keep_generation, generation, members(individuals))

    def batch(self, generation: int, indices: list[int], result: BatchResult) -> None:
        fitness = dict(zip(indices, result.fitness.tolist(), strict=True))
        measures = dict(zip(indices, result.records(), strict=True))
        seconds_each = result.seconds / max(1, len(indices))
        self.landed.append(Landed(fitness, result.worker, seconds_each, measures))
        if self._due():
            self._save(generation)

    def _due(self) -> bool:
        return time.monotonic() - self.written >= self.driving.save_seconds

    def _save(self, generation: int) -> None:
        """Write the fitness that landed and waits (one statement for all its batches)."""
        landed, self.landed = self.landed, []
        self.written = time.monotonic()
        self._fenced(store.driving.save_fitness, generation, landed)

    def _fenced(self, write, *args):  # type: ignore[no-untyped-def]
        """`write(db, run, lease, *args)`; a lost lease stops the driver."""
        try:
            return write(self.db, self.run_id, self.driving.lease, *args)
        except LeaseLostError as lost:
            self.stop(str(lost))
            raise Stop(self.reason) from None

    # -- the loop ------------------------------------------------------------------------------

    def run(self) -> None:
        try:
            self._drive()
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
        if not self.landed or self.generation is None:
            return
        try:
            self._save(self.generation)
        except Stop:  # the lease is gone (cancelled, taken over): the write was refused
            pass
        except (OperationalError, InterfaceError, InternalError) as error:
            self.driving.faults.record(error, f"run {self.run_id}")

    def _drive(self) -> None:
        stored_config, stored_state = store.driving.load(self.db, self.run_id)
        config = RunConfig.model_validate(stored_config)
        algorithm = make_strategy(config.ga_config(), config.make_encoding())
        engine = Engine(
            algorithm, config.sim, self.driving.batch_size, self.driving.in_flight, config.objective
        )
        state = GAState.from_json(stored_state) if stored_state else algorithm.start(config.seed)
        cache, measures = store.driving.known_fitness(self.db, self.run_id, state.generation)
        while not algorithm.done(state):
            self.check()
            self.generation = state.generation
            step = engine.step(state, cache, self.driving.evaluator, self, self.key, measures)
            state = step.state
            upcoming: list[Individual] = []
            if not algorithm.done(state):  # bred now, kept by the same commit
                upcoming = algorithm.ask(state)
                state = replace(state, current=upcoming)
            self._commit(step, upcoming)

    def _commit(self, step: Step, upcoming: list[Individual]) -> None:
        """The generation's fitness, statistics, GA state and counters and the next generation's
        members, all or nothing."""
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
            done=not upcoming,
            seconds=step.seconds,
            upcoming=members(upcoming),
        )
        self.landed, self.written = [], time.monotonic()
        self._fenced(store.driving.commit_generation, commit)
        self.kept = step.stats.generation + 1 if upcoming else None
        self.driving.faults.clear()  # a generation committed: the database takes writes


def members(individuals: list[Individual]) -> list[dict[str, Any]]:
    """Individuals as the store keeps them."""
    return [
        {"genome": EncodedJSON(item.genome.canonical), "genome_hash": item.genome.hash,
         "operator": item.operator, "parents": EncodedJSON(parents_text(item.parents))}
        for item in individuals
    ]  # fmt: skip


class Coordinator:
    """Schedules runs onto drivers (at most `max_running` at once) and heartbeats their leases."""

    def __init__(
        self,
        db: Database,
        evaluator: Evaluator,
        *,
        max_running: int = 2,
        batch_size: int = BATCH_SIZE,
        in_flight: int = IN_FLIGHT,
        save_seconds: float = SAVE_SECONDS,
        lease_seconds: float = 15.0,
        poll_seconds: float = 0.5,
    ) -> None:
        self.db = db
        self.evaluator = evaluator
        self.max_running = max_running
        self.lease_seconds = lease_seconds
        self.poll_seconds = poll_seconds
        self.owner = f"{socket.gethostname()}:{os.getpid()}:{uuid.uuid4().hex[:8]}"
        self.stopping = threading.Event()
        lease = Lease(self.owner, lease_seconds)
        self.faults = Faults()
        self.driving = Driving(
            db, evaluator, lease, batch_size, in_flight, save_seconds, self.stopping, self.faults
        )
        self._wake = threading.Event()
        self._drivers: dict[int, tuple[RunDriver, threading.Thread]] = {}
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self.ticks = 0  # scheduling rounds done: tests wait on them instead of sleeping
        self._ticked = threading.Condition()

    # -- lifecycle -----------------------------------------------------------------------------

    def start(self) -> None:
        self._thread = threading.Thread(target=self._loop, name="coordinator", daemon=True)
        self._thread.start()

    def stop(self, timeout: float = 10.0) -> None:
        """Stop driving, wait for drivers, and hand their runs over at once."""
        self.stopping.set()
        self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)
        with self._lock:
            drivers = list(self._drivers.values())
        for driver, _thread in drivers:
            driver.alarm.set()  # a driver waiting on batches stops now
        for _driver, thread in drivers:
            thread.join(timeout)
        try:
            store.leases.release_all(self.db, self.owner)
        except Exception:  # database away: the leases expire by themselves
            log.exception("could not release leases")

    def wake(self) -> None:
        """A run was queued: schedule now rather than at the next poll."""
        self._wake.set()

    def cancel(self, run_id: int) -> None:
        with self._lock:
            entry = self._drivers.get(run_id)
        if entry is not None:
            entry[0].stop("cancelled")

    def join(self, run_id: int, timeout: float) -> bool:
        """Wait until the run's driver has stopped (True), or `timeout` passes (False)."""
        with self._lock:
            entry = self._drivers.get(run_id)
        if entry is not None:
            entry[1].join(timeout)
            return not entry[1].is_alive()
        return True

    def wait_ticks(self, rounds: int, timeout: float) -> bool:
        """Wait until the scheduler has looked `rounds` more times (True) or `timeout` passes."""
        with self._ticked:
            target = self.ticks + rounds
            return self._ticked.wait_for(lambda: self.ticks >= target, timeout)

    @property
    def active(self) -> list[int]:
        with self._lock:
            return sorted(self._drivers)

    # -- scheduling ----------------------------------------------------------------------------

    def _loop(self) -> None:
        last_heartbeat, quiet = 0.0, 0  # quiet: looks in a row that found no run to start
        while not self.stopping.is_set():
            try:
                if time.monotonic() - last_heartbeat >= self.lease_seconds / 3:
                    self._heartbeat()
                    last_heartbeat = time.monotonic()
                quiet = min(quiet + 1, QUIET_BACKOFF) if self._schedule() else 0
            except (OperationalError, InterfaceError, InternalError) as error:  # next tick again
                self.faults.record(error, "coordinator")
            except Exception:
                log.exception("coordinator tick failed")
            with self._ticked:
                self.ticks += 1
                self._ticked.notify_all()
            if self._wake.wait(self._pause(quiet, last_heartbeat)):
                quiet = 0
            self._wake.clear()

    def _pause(self, quiet: int, last_heartbeat: float) -> float:
        """Seconds until the next tick: `poll_seconds` (at most a third of the lease), doubled
        for each look in a row that found nothing up to QUIET_BACKOFF times (an idle look costs
        a query and a wake-up), but not past the next heartbeat."""
        tick = min(self.poll_seconds, self.lease_seconds / 3)
        heartbeat_due = last_heartbeat + self.lease_seconds / 3 - time.monotonic()
        return min(tick * min(2**quiet, QUIET_BACKOFF), max(heartbeat_due, tick))

    def _heartbeat(self) -> None:
        with self._lock:
            drivers = [driver for driver, _ in self._drivers.values()]
        for driver in drivers:
            if not store.leases.renew(self.db, driver.run_id, self.owner, self.lease_seconds):
                driver.stop("lease lost or run no longer running")

    def _schedule(self) -> bool:
        """Start drivers for waiting runs while this coordinator has room; True when it looked
        and found none to take (an idle look, after which the next one may wait longer)."""
        with self._lock:
            for run_id, (_driver, thread) in list(self._drivers.items()):
                if not thread.is_alive():
                    del self._drivers[run_id]
            free = self.max_running - len(self._drivers)
            busy = set(self._drivers)
        if free <= 0:
            return False
        idle = True
        for run_id in store.leases.candidates(self.db, free + len(busy)):
            if free <= 0 or self.stopping.is_set():
                break
            if run_id in busy or not store.leases.acquire(
                self.db, run_id, self.owner, self.lease_seconds
            ):
                continue
            self.faults.clear()  # it took a write: the database is writable again
            driver = RunDriver(self.driving, run_id)
            thread = threading.Thread(
                target=self._drive, args=(driver,), name=f"run-{run_id}", daemon=True
            )
            with self._lock:  # started under the lock: `join` never meets it unstarted
                self._drivers[run_id] = (driver, thread)
                thread.start()
            free, idle = free - 1, False
            log.info("run %s: driving (owner %s)", run_id, self.owner)
        return idle

    def _drive(self, driver: RunDriver) -> None:
        try:
            driver.run()
        finally:
            self._wake.set()  # its slot is free: look for the next run now
