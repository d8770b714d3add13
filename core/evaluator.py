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
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any, Self

import numpy as np

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
    instead of one batch of 4 leaving the others idle at the generation barrier: the sizes the
    step's `Flights.portion` gives a row asked at once on idle workers, batch after batch."""
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
    """16 hex digits naming a batch by its robots' names (the step's: their genome hashes,
    cheaper than encoding every file again)."""
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
