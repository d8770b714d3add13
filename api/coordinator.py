"""The coordinator: drives runs generation by generation inside the API process.

For each run it owns (see `store.leases`) it runs the one step of
`softevo.core.search.generation` with persistence around it (`RunDriver`): the first
generation's births are kept with the run's first write and a row's commit keeps the next's,
batches' fitness is saved as it lands (a batch that lands within `save_seconds` of the run's
last write waits for the next one, so a generation of quick batches costs one transaction, not
one per batch), and the row (its remaining fitness, statistics, the strategy state, the run's
counters, and the next row's births, bred at once) is committed in one transaction. The
strategy state stored with the last committed row is all a successor needs: generation g is
bred from (seed, g) and generation g-1 alone, so a run taken over after a crash regenerates
the same individuals, re-evaluates only those without fitness and ends with the same learning
curve as an undisturbed run.
"""

from __future__ import annotations

import logging
import os
import socket
import threading
import time
import uuid

from sqlalchemy.exc import InterfaceError, InternalError, OperationalError

from softevo.api import store
from softevo.api.db import Database
from softevo.api.driver import Driving, RunDriver
from softevo.api.faults import Faults
from softevo.api.store.driving import Lease
from softevo.core.evaluator import Evaluator
from softevo.core.limits import BATCH_SIZE, IN_FLIGHT, SAVE_SECONDS

log = logging.getLogger("softevo.coordinator")

#: While its looks for runs to start find none, the scheduler doubles its pause up to this many
#: `poll_seconds` (never past a heartbeat): an idle service looks every few seconds, not twice a
#: second. A run queued through this process, or a driver ending, wakes it at once.
QUIET_BACKOFF = 8


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
