"""The evaluator interface, apart from its backends so that importing it loads no physics.

The generation step (`softevo.core.search.generation`) only sees `Evaluator`: robot files in (plain
`softevo.robot/1` dicts), speeds out (m/s; NaN for a robot that failed, never 0). Backends: the
in-process serial evaluator and local process pool (`softevo.core.physics.evaluation`), and RQ
workers on Redis (`softevo.worker.evaluator`). A robot's fitness does not depend on which backend,
process or batch simulated it, so every backend gives the same learning curve.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import threading
import time
from abc import ABC, abstractmethod
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, Self

import numpy as np

from softevo.core.limits import BATCH_SIZE, IN_FLIGHT
from softevo.core.nulls import Record, from_null, from_null_record, from_nulls

#: The job function's output, JSON-safe: `fitness`, a number or None (failed) per robot,
#: `measures`, a record per robot (name -> number or None; None: no record), see `BatchResult`,
#: and `texts`, each record's JSON text (`record_text`; None: no record), which the service
#: stores as it came instead of encoding the record again (optional: a worker of the release
#: before texts sends none).
Measures = dict[str, list[Any]]


@dataclass(frozen=True)
class BatchResult:
    """One batch's fitness (NaN = failed), who evaluated it, how long it took (s), and each
    robot's record of measures (`SimResult.measures`: name -> value, NaN = not measured; empty
    for a robot that could not be built; None: no records at all), which objectives and
    behavioural descriptors read by name."""

    fitness: np.ndarray
    worker: str
    seconds: float
    measures: list[dict[str, float]] | None = None

    @classmethod
    def measured(cls, measured: Measures, worker: str, seconds: float) -> BatchResult:
        """From the job function's output (`Measures`); a worker of the release before records
        sent a `heading` list instead, which becomes a record of that one measure."""
        fitness = from_nulls(measured["fitness"])
        if "measures" in measured:
            records = [from_null_record(record) for record in measured["measures"]]
            for record, text in zip(records, measured.get("texts") or (), strict=False):
                if text is not None and isinstance(record, Record):
                    record.text = text  # the store writes it as it came
        elif "heading" in measured:
            records = [{"heading": from_null(value)} for value in measured["heading"]]
        else:
            records = None
        return cls(fitness, worker, seconds, records)

    def records(self) -> list[dict[str, float]]:
        """Every robot's record, empty where none was measured."""
        if self.measures is None:
            return [{} for _ in range(len(self.fitness))]
        return self.measures


def well_formed(measured: dict[str, Any], robots: int) -> bool:
    """A job's output that `BatchResult.measured` takes, for `robots` robots: `fitness`, a number
    or None each, and `measures`, a record (name -> number or None) or None each; or, from a
    worker of the release before records, `heading`, a number or None each."""
    if not _numbers(measured.get("fitness"), robots):
        return False
    if "measures" not in measured:
        return _numbers(measured.get("heading"), robots)
    records = measured["measures"]
    return (
        isinstance(records, list)
        and len(records) == robots
        and all(
            record is None
            or (isinstance(record, dict) and _numbers(list(record.values()), len(record)))
            for record in records
        )
        and ("texts" not in measured or _texts(measured["texts"], records))
    )


def _texts(texts: Any, records: list[dict[str, Any] | None]) -> bool:
    """Each record's JSON text, or None: a text that reads back as exactly its record (so what
    the service stores is what the strategies were told), none for a robot without one."""
    if not isinstance(texts, list) or len(texts) != len(records):
        return False
    for text, record in zip(texts, records, strict=True):
        if text is None:
            continue
        if record is None or not isinstance(text, str):
            return False
        try:
            if json.loads(text, parse_constant=_not_a_number) != record:
                return False
        except ValueError:
            return False
    return True


def _not_a_number(name: str) -> Any:
    raise ValueError(f"{name} in a record's text")


def _numbers(values: Any, robots: int) -> bool:
    """A list of a number or None per robot."""
    return (
        isinstance(values, list)
        and len(values) == robots
        and all(v is None or type(v) in (int, float) for v in values)
    )


class BatchDroppedError(RuntimeError):
    """The batch was given up (`Evaluator.drop`, a cancelled run): no fitness, nobody waits."""


def refuse_dropped(key: str, prefixes: set[str]) -> None:
    """Raise `BatchDroppedError` if batch `key` starts with a prefix given to `drop`."""
    if key and any(key.startswith(prefix) for prefix in prefixes):
        raise BatchDroppedError(f"batch {key} was dropped")


class Evaluator(ABC):
    """Simulates batches of robots. Thread-safe: the generation step keeps several batches in
    flight at once (one thread each), and `capacity()` says how many of them run at the same
    moment. A context manager: leaving it closes the backend."""

    @abstractmethod
    def evaluate_batch(
        self, robot_files: Sequence[dict[str, Any]], key: str | None = None
    ) -> BatchResult:
        """The batch's speeds, in input order. `key` names the batch (run, generation,
        content) so a backend can deduplicate it."""

    @abstractmethod
    def capacity(self) -> int:
        """How many batches run at the same moment now (processes, live RQ workers; at least
        1): a generation is cut into at least this many."""

    @abstractmethod
    def close(self) -> None:
        """Free what the backend holds (processes, connections)."""

    def drop(self, key_prefix: str) -> None:  # noqa: B027 - optional: by default a no-op
        """Give up the batches whose key starts with `key_prefix` (a cancelled run's): none of
        them starts any more, one running stops where the backend can stop it, and their
        `evaluate_batch` calls raise `BatchDroppedError` within seconds. By default nothing is
        given up: an in-process evaluator finishes what it began."""

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def split_evenly(items: Sequence[int], size: int, workers: int) -> list[list[int]]:
    """Contiguous batches of at most `size`, but at least `workers` of them (when there are that
    many items) and of near-equal length, so a generation's few new robots keep every worker busy
    instead of one batch of 4 leaving the others idle at the generation barrier."""
    n = len(items)
    if n == 0:
        return []
    count = batch_count(n, size, workers)
    bounds = [-(-i * n // count) for i in range(count + 1)]  # ceil: longer batches first
    return [list(items[a:b]) for a, b in itertools.pairwise(bounds)]


def batch_count(n: int, size: int, workers: int) -> int:
    """How many batches `split_evenly` cuts `n` (> 0) items into: enough for batches of at most
    `size`, and at least `workers`, but no more than the items."""
    return min(n, max(math.ceil(n / max(1, size)), workers))


def batch_digest(robot_files: Sequence[dict[str, Any]]) -> str:
    """16 hex digits naming a batch's content, the same in every process and on every machine."""
    canonical = json.dumps(list(robot_files), separators=(",", ":"), sort_keys=True)
    return hashlib.sha256(canonical.encode()).hexdigest()[:16]


def names_digest(names: Sequence[str]) -> str:
    """16 hex digits naming a batch by its robots' names (`evaluate_in_batches`' `names`)."""
    return hashlib.sha256(",".join(names).encode()).hexdigest()[:16]


def _new_hands() -> ThreadPoolExecutor:
    """Threads are made only when none is idle: as many as batches were ever out at once."""
    return ThreadPoolExecutor(max_workers=256, thread_name_prefix="batch")


#: The threads that hand batches to evaluators, shared by every step of the process: started
#: when first needed and kept, so a generation does not start its few threads afresh (each call
#: still keeps at most its own number of batches handed over at once).
_HANDS = _new_hands()


def _forget_hands() -> None:
    """A forked child has none of its parent's threads (its pool would wait on them forever):
    it starts its own."""
    global _HANDS
    _HANDS = _new_hands()


os.register_at_fork(after_in_child=_forget_hands)


def hand_over(work: Callable[..., None], *args: Any) -> None:
    """Run `work(*args)` on one of the shared batch threads (`_HANDS`)."""
    _HANDS.submit(work, *args)


#: Longest the step's thread waits between calls of `check` while batches run, when nothing
#: (the last batch, a due one, the caller's alarm) wakes it sooner.
CHECK_SECONDS = 1.0

#: What a batch thread hands back: the batch's positions, its result or what it raised.
Landing = tuple[list[int], BatchResult | None, BaseException | None]


class _Landings:
    """The batches of one call that landed and were not taken in yet. The step's thread is woken
    when the last one lands or one fails, when one lands once the caller wants batches at once
    (`due`, a `time.monotonic()`: to save them), or by the caller's `alarm` (a stop); otherwise
    it sleeps up to CHECK_SECONDS: a wake-up costs this process more CPU than taking batches in."""

    def __init__(self, expected: int, alarm: threading.Event | None) -> None:
        self.expected, self.arrived, self.failed = expected, 0, False
        self.items: list[Landing] = []
        self.due: float | None = None
        self.lock = threading.Lock()
        self.ready = threading.Event() if alarm is None else alarm
        self.ready.clear()  # a stop that came before is seen by the `check` that comes first

    def put(self, landing: Landing) -> None:
        with self.lock:
            self.items.append(landing)
            self.arrived += 1
            self.failed = self.failed or landing[2] is not None
            if self._finished() or (self.due is not None and time.monotonic() >= self.due):
                self.ready.set()

    def _finished(self) -> bool:
        return self.failed or self.arrived == self.expected

    def take(self, due: float | None) -> list[Landing]:
        """What landed, once the rest is in (or one failed) or once `due` passed (None: only at
        the end); [] when the alarm rang or CHECK_SECONDS passed before."""
        with self.lock:
            self.due, wait = due, CHECK_SECONDS
            if self.items and due is not None:
                wait = min(wait, max(0.0, due - time.monotonic()))
        self.ready.wait(wait)
        with self.lock:
            finished = self._finished()
            if not finished:  # (a stop that rings now is seen by the next `check`)
                self.ready.clear()
            if not finished and (due is None or time.monotonic() < due):
                return []
            items, self.items = self.items, []
        return items

    def drain(self) -> list[Landing]:
        """Whatever landed, at once."""
        with self.lock:
            items, self.items = self.items, []
        return items


def _hand_over(
    evaluator: Evaluator,
    files: list[dict[str, Any]],
    names: Sequence[str] | None,
    key: str,
    waiting: deque[list[int]],
    landed: _Landings,
    stopped: threading.Event,
) -> None:
    """One of an `evaluate_in_batches` call's threads: hands its batches over in order, one at a
    time, until none is left or the step stopped (it goes straight on to the next batch: no
    other thread is woken for it)."""
    while not stopped.is_set():
        try:
            batch = waiting.popleft()
        except IndexError:
            return
        chunk = [files[i] for i in batch]
        digest = batch_digest(chunk) if names is None else names_digest([names[i] for i in batch])
        try:
            landed.put((batch, evaluator.evaluate_batch(chunk, f"{key}-{digest}"), None))
        except BaseException as error:  # the step raises it; the others stop handing over
            landed.put((batch, None, error))
            return


def evaluate_in_batches(
    evaluator: Evaluator,
    robot_files: Sequence[dict[str, Any]],
    key: str = "local",
    *,
    batch_size: int = BATCH_SIZE,
    in_flight: int = IN_FLIGHT,
    check: Callable[[], float | None] | None = None,
    on_batch: Callable[[list[int], BatchResult], None] | None = None,
    names: Sequence[str] | None = None,
    alarm: threading.Event | None = None,
) -> np.ndarray:
    """Every file's speed (in order), evaluated in batches of at most `batch_size`, at least
    `evaluator.capacity()` of them, at most `in_flight` (and two per worker) at once: as many
    threads, each handing over the next batch when its last one lands. `check` is called while
    they run, at least every CHECK_SECONDS and at once when another thread sets `alarm`: it
    raises to stop (batches not yet handed to the evaluator are dropped; those that landed are
    given to `on_batch` first), or returns the `time.monotonic()` from which `on_batch` should
    hear of a batch as soon as it lands (None: at the end is soon enough). `on_batch` hears of
    each batch (its positions in `robot_files`, its result) by then, or at the end. A batch's
    key is `key`, a dash and a digest of its content: of its files' canonical JSON, or of their
    `names` where the caller has them (one per file, each naming its content within `key`, such
    as a generation's genome hashes: cheaper than encoding every file again)."""
    files = list(robot_files)
    if names is not None and len(names) != len(files):
        raise ValueError(f"{len(names)} names for {len(files)} robot files")
    fitness = np.full(len(files), np.nan)
    if not files:
        return fitness
    capacity = evaluator.capacity()
    waiting = deque(split_evenly(range(len(files)), batch_size, capacity))
    # at most two batches per worker handed over at once: enough to keep every worker busy, and
    # when `check` stops the step (a cancel) the batches not yet handed over are dropped
    threads = max(1, min(len(waiting), in_flight, 2 * capacity))
    outstanding = len(waiting)
    landed, stopped = _Landings(outstanding, alarm), threading.Event()
    try:
        for _ in range(threads):
            _HANDS.submit(_hand_over, evaluator, files, names, key, waiting, landed, stopped)
        while outstanding:
            due = None if check is None else check()
            for batch, result, error in landed.take(due):
                outstanding -= 1
                if error is not None:
                    raise error
                assert result is not None
                if on_batch is not None:
                    on_batch(batch, result)
                fitness[batch] = np.asarray(result.fitness, dtype=np.float64)
    except BaseException:
        if on_batch is not None:  # a stop: what landed is not lost with the step
            for batch, result, _error in landed.drain():
                if result is not None:
                    on_batch(batch, result)
        raise
    finally:
        stopped.set()  # batches not handed over yet never will be
    return fitness
