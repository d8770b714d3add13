"""The GA coordinator: drives runs generation by generation inside the API process.

For each generation of a run it owns (see `api.leases`): ask the GA -> persist the individuals
-> evaluate what has no fitness, batch by batch, through the `Evaluator` interface, saving each
batch's fitness as it comes -> tell the GA -> commit the generation (its statistics, the GA state,
the run's counters) in one transaction. The GA state stored with the last committed generation is
all a successor needs: generation g is bred from (seed, g) and generation g-1 alone, so a run taken
over after a crash regenerates the same individuals, re-evaluates only those without fitness and
ends with the same learning curve as an undisturbed run.

Counting is the same as `softevo run`'s (`core.evolution`): a genome seen in an earlier generation
of the run is not simulated again (`saved`); within a generation, each distinct new genome is
simulated once (`evaluations`).
"""

from __future__ import annotations

import logging
import math
import os
import socket
import threading
import time
import uuid
from collections.abc import Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait
from typing import Any

import numpy as np
from sqlalchemy import select, update
from sqlalchemy.exc import InterfaceError, OperationalError

from softevo.api import leases
from softevo.api.db import Database
from softevo.api.models import Generation, Individual, Run
from softevo.api.storage import now
from softevo.core.config import RunConfig
from softevo.core.evaluator import BatchResult, Evaluator, batch_digest, split_evenly
from softevo.core.ga.algorithm import GAState, GeneticAlgorithm
from softevo.core.ga.algorithm import Individual as GAIndividual
from softevo.core.ga.stats import GenerationStats
from softevo.core.limits import BATCH_SIZE
from softevo.core.robot_file import robot_to_json

log = logging.getLogger("softevo.coordinator")


class Stop(Exception):  # noqa: N818 - a signal, not an error
    """The driver must stop: shutdown, cancellation or a lost lease."""


def _or_nan(value: float | None) -> float:
    return math.nan if value is None else value


def _or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


class RunDriver:
    """Drives one run while its coordinator holds the lease."""

    def __init__(self, coordinator: Coordinator, run_id: int) -> None:
        self.coordinator = coordinator
        self.db = coordinator.db
        self.run_id = run_id
        self.abort = threading.Event()
        self.reason = ""

    # -- control -------------------------------------------------------------------------------

    def stop(self, reason: str) -> None:
        self.reason = reason
        self.abort.set()

    def _check(self) -> None:
        if self.abort.is_set():
            raise Stop(self.reason)
        if self.coordinator.stopping.is_set():
            raise Stop("shutdown")

    def _fenced(self, session: Any) -> None:
        c = self.coordinator
        if not leases.owns(session, self.run_id, c.owner, c.settings_lease):
            self.stop("lease lost or run no longer running")
            raise Stop(self.reason)

    # -- the loop ------------------------------------------------------------------------------

    def run(self) -> None:
        try:
            self._drive()
        except Stop as stop:
            log.info("run %s: driver stopped (%s)", self.run_id, stop)
        except (OperationalError, InterfaceError):  # database away: the lease expires, retried
            log.exception("run %s: database error; the run will be taken over", self.run_id)
        except Exception as error:  # any bug or evaluator failure fails the run
            log.exception("run %s failed", self.run_id)
            self._fail(f"{type(error).__name__}: {error}")

    def _fail(self, message: str) -> None:
        try:
            with self.db.write() as session:
                session.execute(
                    update(Run)
                    .where(Run.id == self.run_id, Run.lease_owner == self.coordinator.owner)
                    .values(status="failed", error=message[:2000], finished_at=now(),
                            lease_owner=None, lease_expires=None)
                )  # fmt: skip
        except Exception:  # the database itself is away; the lease will expire
            log.exception("run %s: could not record the failure", self.run_id)

    def _drive(self) -> None:
        with self.db.read() as session:
            row = session.get(Run, self.run_id)
            assert row is not None
            config = RunConfig.model_validate(row.config)
            stored_state = row.ga_state
        state = GAState.from_json(stored_state) if stored_state else GAState(seed=config.seed)
        algorithm = GeneticAlgorithm(config.ga_config(), config.make_encoding(), state)
        cache = self._cache_before(state.generation)
        while not algorithm.done:
            self._check()
            started = time.perf_counter()
            individuals = algorithm.ask()
            generation = state.generation
            have = self._persist_individuals(generation, individuals)
            hashes = [individual.genome.hash for individual in individuals]
            first: dict[str, int] = {}
            for index, genome_hash in enumerate(hashes):
                if genome_hash not in cache and genome_hash not in first:
                    first[genome_hash] = index
            todo = [index for index in first.values() if index not in have]
            fitness = {index: have[index] for index in first.values() if index in have}
            fitness.update(self._evaluate(config, generation, individuals, todo))
            cache.update({hashes[index]: value for index, value in fitness.items()})
            values = np.array([cache[h] for h in hashes], dtype=np.float64)
            evaluations = len(first)
            stats = algorithm.tell(
                values, evaluations=evaluations, saved=len(individuals) - evaluations
            )
            self._commit(stats, algorithm, values, set(first.values()), started)

    def _cache_before(self, generation: int) -> dict[str, float]:
        """Fitness of every genome evaluated in generations before `generation` (NaN = failed)."""
        with self.db.read() as session:
            rows = session.execute(
                select(Individual.genome_hash, Individual.fitness).where(
                    Individual.run_id == self.run_id,
                    Individual.generation < generation,
                    Individual.status != "pending",
                )
            )
            return {genome_hash: _or_nan(fitness) for genome_hash, fitness in rows}

    def _persist_individuals(
        self, generation: int, individuals: list[GAIndividual]
    ) -> dict[int, float]:
        """Insert generation `generation`'s individuals (once); return fitness already saved."""
        with self.db.write() as session:
            self._fenced(session)
            rows = session.scalars(
                select(Individual).where(
                    Individual.run_id == self.run_id, Individual.generation == generation
                )
            ).all()
            if not rows:
                session.add_all(
                    Individual(
                        run_id=self.run_id, generation=generation, index=index,
                        genome=item.genome.to_json(), genome_hash=item.genome.hash,
                        operator=item.operator, parents=list(item.parents), status="pending",
                    )
                    for index, item in enumerate(individuals)
                )  # fmt: skip
                return {}
            stored = {row.index: row.genome_hash for row in rows}
            expected = {index: item.genome.hash for index, item in enumerate(individuals)}
            if stored != expected:
                raise RuntimeError(
                    f"generation {generation} in the database differs from the one the GA "
                    "regenerated from the run's seed; refusing to mix them"
                )
            return {
                row.index: _or_nan(row.fitness)
                for row in rows
                if row.status in ("evaluated", "failed")
            }

    def _evaluate(
        self,
        config: RunConfig,
        generation: int,
        individuals: list[GAIndividual],
        todo: Sequence[int],
    ) -> dict[int, float]:
        """Evaluate `todo` in batches, several at once, saving each batch's fitness as it lands."""
        c = self.coordinator
        results: dict[int, float] = {}
        if not todo:
            return results
        encoding = config.make_encoding()
        batches = split_evenly(todo, c.batch_size, c.evaluator.workers())
        executor = ThreadPoolExecutor(max_workers=c.parallel_batches, thread_name_prefix="batch")
        try:
            futures: dict[Future[BatchResult], list[int]] = {}
            for batch in batches:
                files = [
                    robot_to_json(encoding.to_robot(individuals[i].genome, config.sim))
                    for i in batch
                ]
                key = f"run{self.run_id}-gen{generation}-{batch_digest(files)}"
                futures[executor.submit(c.evaluator.evaluate_batch, files, key)] = batch
            pending = set(futures)
            while pending:
                self._check()
                done, pending = wait(pending, timeout=0.2, return_when=FIRST_COMPLETED)
                for future in done:
                    batch, result = futures[future], future.result()
                    values = np.asarray(result.fitness, dtype=np.float64)
                    self._save_fitness(generation, batch, values, result)
                    results.update(zip(batch, values.tolist(), strict=True))
        finally:
            executor.shutdown(wait=False, cancel_futures=True)
        return results

    def _save_fitness(
        self, generation: int, batch: list[int], values: np.ndarray, result: BatchResult
    ) -> None:
        seconds = result.seconds / max(1, len(batch))
        with self.db.write() as session:
            self._fenced(session)
            for index, value in zip(batch, values.tolist(), strict=True):
                session.execute(
                    update(Individual)
                    .where(
                        Individual.run_id == self.run_id,
                        Individual.generation == generation,
                        Individual.index == index,
                        Individual.status == "pending",  # a second fitness is never written
                    )
                    .values(
                        fitness=_or_none(value),
                        status="evaluated" if math.isfinite(value) else "failed",
                        eval_seconds=seconds,
                        worker=result.worker[:128],
                        evaluated_at=now(),
                    )
                )

    def _commit(
        self,
        stats: GenerationStats,
        algorithm: GeneticAlgorithm,
        values: np.ndarray,
        evaluated: set[int],
        started: float,
    ) -> None:
        """The generation's statistics, cached fitness, GA state and counters, all or nothing."""
        seconds = time.perf_counter() - started
        state = algorithm.state
        stored = state.to_json()
        stored["history"] = []  # the curve lives in `generations`; keep the row small
        done = algorithm.done
        best = state.best
        with self.db.write() as session:
            self._fenced(session)
            for index, value in enumerate(values.tolist()):
                if index in evaluated:
                    continue
                session.execute(
                    update(Individual)
                    .where(
                        Individual.run_id == self.run_id,
                        Individual.generation == stats.generation,
                        Individual.index == index,
                        Individual.status == "pending",
                    )
                    .values(fitness=_or_none(value), status="cached", evaluated_at=now())
                )
            row = stats.to_json()
            session.add(
                Generation(
                    run_id=self.run_id,
                    **{k: row[k] for k in (
                        "generation", "best", "mean", "median", "min", "std", "best_so_far",
                        "diversity", "size", "failed", "evaluations", "saved")},
                    seconds=seconds,
                    committed_at=now(),
                )
            )  # fmt: skip
            run = session.get(Run, self.run_id)
            assert run is not None
            run.ga_state = stored
            run.generations_done = stats.generation + 1
            run.evaluations += stats.evaluations
            run.saved += stats.saved
            run.compute_seconds += seconds
            if best is not None:
                run.best_fitness, run.best_generation = best[1], best[2]
            if done:
                run.status, run.finished_at = "completed", now()
                run.lease_owner, run.lease_expires = None, None


class Coordinator:
    """Schedules runs onto drivers (at most `max_running` at once) and heartbeats their leases."""

    def __init__(
        self,
        db: Database,
        evaluator: Evaluator,
        *,
        max_running: int = 2,
        batch_size: int = BATCH_SIZE,
        parallel_batches: int | None = None,
        lease_seconds: float = 15.0,
        poll_seconds: float = 0.5,
    ) -> None:
        self.db = db
        self.evaluator = evaluator
        self.max_running = max_running
        self.batch_size = batch_size
        self.parallel_batches = parallel_batches or max(1, evaluator.concurrency)
        self.settings_lease = lease_seconds
        self.poll_seconds = poll_seconds
        host = socket.gethostname()
        self.owner = f"{host}:{os.getpid()}:{uuid.uuid4().hex[:8]}"
        self.stopping = threading.Event()
        self._wake = threading.Event()
        self._drivers: dict[int, tuple[RunDriver, threading.Thread]] = {}
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None

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
        for _driver, thread in list(self._drivers.values()):
            thread.join(timeout)
        try:
            leases.release_all(self.db, self.owner)
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

    @property
    def active(self) -> list[int]:
        with self._lock:
            return sorted(self._drivers)

    # -- scheduling ----------------------------------------------------------------------------

    def _loop(self) -> None:
        last_heartbeat = 0.0
        while not self.stopping.is_set():
            try:
                if time.monotonic() - last_heartbeat >= self.settings_lease / 3:
                    self._heartbeat()
                    last_heartbeat = time.monotonic()
                self._schedule()
            except Exception:  # e.g. database away: retry at the next tick
                log.exception("coordinator tick failed")
            self._wake.wait(min(self.poll_seconds, self.settings_lease / 3))
            self._wake.clear()

    def _heartbeat(self) -> None:
        with self._lock:
            drivers = [driver for driver, _ in self._drivers.values()]
        for driver in drivers:
            if not leases.renew(self.db, driver.run_id, self.owner, self.settings_lease):
                driver.stop("lease lost or run no longer running")

    def _schedule(self) -> None:
        with self._lock:
            for run_id, (_driver, thread) in list(self._drivers.items()):
                if not thread.is_alive():
                    del self._drivers[run_id]
            free = self.max_running - len(self._drivers)
            busy = set(self._drivers)
        if free <= 0:
            return
        for run_id in leases.candidates(self.db, free + len(busy)):
            if free <= 0 or self.stopping.is_set():
                break
            if run_id in busy or not leases.acquire(
                self.db, run_id, self.owner, self.settings_lease
            ):
                continue
            driver = RunDriver(self, run_id)
            thread = threading.Thread(target=driver.run, name=f"run-{run_id}", daemon=True)
            with self._lock:
                self._drivers[run_id] = (driver, thread)
            thread.start()
            free -= 1
            log.info("run %s: driving (owner %s)", run_id, self.owner)
