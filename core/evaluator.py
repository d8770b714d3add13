"""The evaluator interface, apart from its backends so that importing it loads no physics.

The genetic algorithm and the coordinator only see `Evaluator`: robot files in (plain
`softevo.robot/1` dicts), speeds out (m/s; NaN for a robot that failed, never 0). Backends: the
in-process serial evaluator and local process pool (`core.evaluation`), and RQ workers on Redis
(`worker.evaluator`). A robot's fitness does not depend on which backend, process or batch
simulated it, so every backend gives the same learning curve.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np


@dataclass(frozen=True)
class BatchResult:
    """One batch's speeds (m/s, NaN = failed), who evaluated it and how long it took (s)."""

    fitness: np.ndarray
    worker: str
    seconds: float


class Evaluator(Protocol):
    """Simulates batches of robots; several batches may be in flight at once (`concurrency`)."""

    #: How many batches the caller should keep in flight to keep this evaluator busy.
    concurrency: int

    def evaluate(self, robot_files: Sequence[dict[str, Any]]) -> np.ndarray: ...

    def workers(self) -> int:
        """How many batches this evaluator runs at the same moment now (processes, live RQ
        workers; at least 1): the coordinator cuts a generation into at least this many."""
        ...

    def evaluate_batch(
        self, robot_files: Sequence[dict[str, Any]], key: str | None = None
    ) -> BatchResult:
        """`key` names the batch (run, generation, content) so a backend can deduplicate it."""
        ...

    def close(self) -> None: ...


def split_evenly(items: Sequence[int], size: int, workers: int) -> list[list[int]]:
    """Contiguous batches of at most `size`, but at least `workers` of them (when there are that
    many items) and of near-equal length, so a generation's few new robots keep every worker busy
    instead of one batch of 4 leaving the others idle at the generation barrier."""
    n = len(items)
    if n == 0:
        return []
    count = min(n, max(math.ceil(n / max(1, size)), workers))
    bounds = [-(-i * n // count) for i in range(count + 1)]  # ceil: longer batches first
    return [list(items[a:b]) for a, b in itertools.pairwise(bounds)]


def batch_digest(robot_files: Sequence[dict[str, Any]]) -> str:
    """16 hex digits naming a batch's content, the same in every process and on every machine."""
    canonical = json.dumps(list(robot_files), separators=(",", ":"), sort_keys=True)
    return hashlib.sha256(canonical.encode()).hexdigest()[:16]
