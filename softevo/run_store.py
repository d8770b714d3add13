"""`softevo run`'s persistence: the service's store, on SQLite in the output folder (`run.db`),
driven by the service's `RunDriver` on the local pool. A run is then kept, cached, resumed and
taken over by one code path, the service's; the folder's other files are written from the store,
as the API's answers are read from it. A folder written before the store (state.json and
cache.json, no run.db) is checked as before and imported on `--resume`."""

from __future__ import annotations

import contextlib
import json
import os
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from alembic.util.exc import CommandError
from sqlalchemy.exc import SQLAlchemyError

from softevo.api import store
from softevo.api.db import Database
from softevo.api.driver import Driving, RunDriver, Stop
from softevo.api.faults import Faults, reason
from softevo.api.store import folders
from softevo.api.store.driving import Lease
from softevo.core.config import ConfigError, RunConfig, resolve
from softevo.core.evolution import Evolution
from softevo.core.limits import BATCH_SIZE, IN_FLIGHT, SAVE_SECONDS
from softevo.core.search.generation import Step
from softevo.core.search.state import StrategyState
from softevo.core.search.stats import GenerationStats
from softevo.results import (
    read_population,
    read_resumable,
    write_json,
    write_population,
    write_results,
)
from softevo.resume_checks import check_folder

DATABASE = "run.db"
#: A folder's run is driven by one process; a write renews its lease for this long (s).
LEASE_SECONDS = 15.0


@dataclass(frozen=True)
class Folder:
    """A `softevo run` output folder and the run its store holds."""

    out: Path
    db: Database
    run_id: int

    @property
    def config(self) -> RunConfig:
        return RunConfig.model_validate(folders.db_config(self.db, self.run_id))

    def close(self) -> None:
        """Close the store, its write-ahead log moved into run.db: one file to copy."""
        with contextlib.suppress(SQLAlchemyError):  # a full disk: the log stays, read with it
            folders.checkpoint(self.db)
        self.db.dispose()

    @property
    def done(self) -> int:
        """Generations committed."""
        return self.totals()[0]

    def totals(self) -> tuple[int, int, int, float]:
        """(generations done, evaluations, saved, compute seconds) of the run."""
        return folders.totals(self.db, self.run_id)


def _database(out: Path) -> Database:
    """The folder's store, migrated as the service's is (ValueError: a file that is not one)."""
    path = out / DATABASE
    if path.exists() and not path.is_file():
        raise ValueError(f"{path}: not a file")
    db = Database(f"sqlite:///{path}")
    try:
        folders.check_store(db)
    except (SQLAlchemyError, ValueError) as error:
        db.dispose()
        raise ValueError(f"{path}: not a `softevo run` store ({reason(error)})") from None
    try:
        db.upgrade()
    except CommandError as error:  # a revision this release does not know
        db.dispose()
        raise ValueError(f"{path}: written by another release of softevo ({error})") from None
    except SQLAlchemyError as error:  # a full disk, a read-only folder
        db.dispose()
        raise ValueError(f"{path}: {reason(error)}") from None
    return db


def new(out: Path, config: RunConfig) -> Folder:
    """A new run in `out`, any store left there started afresh (`stored_config` tells the
    caller whose it was first)."""
    _remove_store(out)
    db = _database(out)
    folder = Folder(out, db, store.create_run(db, config).id)
    write_json(out / "config.json", config.to_json())  # the folder names its config at once
    return folder


def stored_config(out: Path) -> dict[str, Any] | None:
    """The config of the run in `out`'s run.db, as it is (not migrated, nothing written); None
    if there is none or it cannot be read."""
    if not (out / DATABASE).is_file():
        return None
    db = Database(f"sqlite:///{out / DATABASE}")
    try:
        run_id = folders.the_run(db)
        return None if run_id is None else folders.db_config(db, run_id)
    except (SQLAlchemyError, TypeError, ValueError):
        return None
    finally:
        db.dispose()


def resume(out: Path, generations: int | None) -> Folder:
    """The stopped run in `out`, to go on to `generations` if given; ValueError (or the folder
    checks' ResumeError) with a one-line reason if it cannot."""
    path = out / DATABASE
    if not path.exists():
        return _imported(out, generations)
    db = _database(out)
    try:
        run_id = folders.the_run(db)
    except SQLAlchemyError as error:
        db.dispose()
        raise ValueError(f"{path}: not a run to go on with ({reason(error)})") from None
    if run_id is None:  # stopped while importing: the files are still whole
        db.dispose()
        return _imported(out, generations)
    folder = Folder(out, db, run_id)
    try:
        stored, state = store.driving.load(db, run_id)
        if state is not None:
            StrategyState.from_json(state)
    except (SQLAlchemyError, KeyError, TypeError, ValueError) as error:
        db.dispose()
        raise ValueError(f"{path}: not a run to go on with ({reason(error)})") from None
    try:
        _check(out, folder, stored, generations)
    except ValueError:
        db.dispose()
        raise
    return folder


def _check(out: Path, folder: Folder, stored: Any, generations: int | None) -> None:
    """The stored run against config.json (but for generations, which a --resume raises first
    in the store), and valid with `generations`."""
    if (out / "config.json").is_file() and _but_generations(config_json(out)) != (
        _but_generations(stored)
    ):
        raise ValueError(
            f"{out}/config.json: not the config of the run in {DATABASE} (edited, or another "
            "run's); cannot resume"
        )
    raised = isinstance(stored, dict) and generations is not None
    try:
        resolve({**stored, "generations": generations} if raised else stored)
    except ConfigError as error:
        raise ValueError(f"{out}/{DATABASE}: {error}") from None
    if generations is not None and generations < folder.done:
        raise ValueError(
            f"{out}: --generations {generations}: the run already has {folder.done} generations"
        )


def config_json(out: Path) -> object:
    """`out`'s config.json as JSON (None: no readable file)."""
    try:
        return json.loads((out / "config.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def _but_generations(config: object) -> object:
    return (
        {k: v for k, v in config.items() if k != "generations"}
        if isinstance(config, dict)
        else config
    )


def _imported(out: Path, generations: int | None) -> Folder:
    """A folder of a release before the store: checked, then its files become the run's rows."""
    check_folder(out, generations)
    rows = _population_rows(out)
    evolution = read_resumable(out, generations)
    rows = [row for row in rows if row["generation"] < evolution.state.generation]
    _remove_store(out)
    db = _database(out)
    known = (evolution.cache, evolution.measures)
    try:
        run_id = folders.import_run(
            db, evolution.config, evolution.state, known, evolution.elapsed, rows
        )
    except BaseException:
        db.dispose()
        _remove_store(out)  # all or nothing: the files are still what --resume reads
        raise
    return Folder(out, db, run_id)


def _population_rows(out: Path) -> list[dict[str, Any]]:
    """population.csv's rows, each (generation, index) once; ValueError naming the file."""
    try:
        rows = read_population(out)
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"{out}/population.csv: not a run's population ({error!r})") from None
    seen = set()
    for row in rows:
        place = (row["generation"], row["index"])
        if place in seen:
            raise ValueError(f"{out}/population.csv: generation {place[0]}, index {place[1]} twice")
        seen.add(place)
    return rows


def _remove_store(out: Path) -> None:
    for suffix in ("", "-wal", "-shm"):
        path = out / f"{DATABASE}{suffix}"
        if path.is_dir():
            raise ValueError(f"{path}: a folder where the run's store goes")
        path.unlink(missing_ok=True)


@dataclass
class Known:
    """The fitness and records of the generations before `before`, read from the store once:
    committed rows never change, so each later read takes the generations since."""

    fitness: dict[str, float] = field(default_factory=dict)
    measures: dict[str, dict[str, float]] = field(default_factory=dict)
    before: int | None = None

    def update(self, folder: Folder, before: int) -> None:
        fitness, measures = store.driving.known_fitness(
            folder.db, folder.run_id, before, self.before
        )
        fitness.pop("", None)  # an imported folder's individuals: no genome, no hash
        measures.pop("", None)
        self.fitness.update(fitness)
        self.measures.update(measures)
        self.before = before


def evolution(folder: Folder, known: Known | None = None) -> Evolution:
    """The run as its store holds it, as an in-process run would hold it: what `Result` and the
    folder's files are made of (`known`: what an earlier call read)."""
    stored_config, stored_state = store.driving.load(folder.db, folder.run_id)
    config = RunConfig.model_validate(stored_config)
    if stored_state is None:
        return Evolution.start(config)
    done, _, _, seconds = folders.totals(folder.db, folder.run_id)
    known = Known() if known is None else known
    known.update(folder, done)
    history = [GenerationStats.from_json(row) for row in folders.history(folder.db, folder.run_id)]
    state = replace(StrategyState.from_json(stored_state), history=history)
    return Evolution.resume(config, state, known.fitness, seconds, known.measures)


class TakenOverError(RuntimeError):
    """Another process drives the folder's run now."""


class _Driver(RunDriver):
    """The service's driver, telling `softevo run` of each generation committed."""

    def __init__(self, driving: Driving, run_id: int, report: Callable[[Step], None]) -> None:
        super().__init__(driving, run_id)
        self.report = report

    def committed(self, step: Step) -> None:
        self.report(step)


def drive(
    folder: Folder,
    workers: int | None,
    generations: int,
    report: Callable[[Step], None],
) -> None:
    """Run the folder's run to `generations` on `workers` local processes, calling `report`
    after each generation is committed. Ctrl-C keeps the fitness that landed, then raises."""
    from softevo.core.physics.evaluation import make_evaluator  # the physics: loaded to run

    owner = f"softevo-run:{socket.gethostname()}:{os.getpid()}"
    folders.take(folder.db, folder.run_id, owner, LEASE_SECONDS, generations)
    evaluator = make_evaluator(workers)
    lease = Lease(owner, LEASE_SECONDS)
    driving = Driving(
        folder.db,
        evaluator,
        lease,
        BATCH_SIZE,
        IN_FLIGHT,
        SAVE_SECONDS,
        threading.Event(),
        Faults(),
    )
    driver = _Driver(driving, folder.run_id, report)
    try:
        driver.drive()
    except KeyboardInterrupt:
        driver.flush()  # what landed of the generation: not simulated again on --resume
        raise
    except Stop as stop:  # another process took the folder's run over (its lease)
        raise TakenOverError(str(stop)) from None
    finally:
        with contextlib.suppress(SQLAlchemyError):  # the store's own error is the one to say
            folders.release(folder.db, folder.run_id, owner)
        evaluator.close()


class Checkpoints:
    """The folder's files, written from the store at most every `seconds` while the run goes
    (rewriting them after every generation would cost time that grows with the run), and at its
    end or interruption (`flush`). population.csv only gets the generations it lacks."""

    def __init__(self, folder: Folder, seconds: float = SAVE_SECONDS) -> None:
        self.folder, self.seconds = folder, seconds
        self.written = time.monotonic()
        self.listed: int | None = None  # generations population.csv holds (None: rewrite it)
        self.known = Known()

    def done(self) -> None:
        if time.monotonic() - self.written >= self.seconds:
            self.flush()

    def flush(self) -> Evolution:
        """Write every file; the run as written."""
        evolution_now = evolution(self.folder, self.known)
        write_results(self.folder.out, evolution_now)
        done = len(evolution_now.state.history)
        # an append cut short (Ctrl-C) leaves `listed` None: the next flush rewrites the file
        listed, self.listed = self.listed, None
        rows = folders.population(self.folder.db, self.folder.run_id, done, _last(listed))
        write_population(self.folder.out, rows, append=listed is not None)
        self.listed, self.written = done, time.monotonic()
        return evolution_now


def _last(listed: int | None) -> int:
    return -1 if listed is None else listed - 1
