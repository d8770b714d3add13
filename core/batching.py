"""Cross-run batching: the batches of every caller (the runs a service drives at once) wait in
one queue, and each task handed to a process holds whole batches of one kind (grid shape and
simulation settings) up to the kernel's SIMD width, whatever run they belong to.

A generation of a paper-voxel run has about five new robots, cut into a batch per process: one
or two robots fill one or two of a kernel call's eight lanes. When every process is busy, the
batches that arrive meanwhile (other runs', or seeds of the same box in a sweep) wait and leave
together as one task, so the machine simulates in fuller SIMD batches. While a process is free,
a batch leaves at once: merging never holds work back from an idle core. A robot's fitness does
not depend on its batch (the kernels are bit-identical across batches), so neither does a curve.
"""

from __future__ import annotations

import json
from collections import deque
from collections.abc import Sequence
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any

from softevo.core.physics.simulate import DEFAULT_LANES


def kind(robot_file: Any) -> str:
    """Robots of one kind run together in the kernel: the same grid shape and settings."""
    if not isinstance(robot_file, dict):
        return "?"
    return json.dumps([robot_file.get("shape"), robot_file.get("sim")], sort_keys=True)


@dataclass(eq=False)
class Request:
    """One caller's batch: its robot files, its key, and the future its caller waits on."""

    files: list[Any]
    key: str
    future: Future[list[float | None]] = field(default_factory=Future)
    attempt: int = 1
    alone: bool = False  # after a failed task: run by itself, so a robot that kills its
    # process is not blamed on the batches it was merged with
    kind: str = ""

    def __post_init__(self) -> None:
        kinds = {kind(file) for file in self.files}
        self.kind = kinds.pop() if len(kinds) == 1 else "mixed"


class Queue:
    """Batches waiting for a process, taken as tasks of whole batches of one kind."""

    def __init__(self, lanes: int = DEFAULT_LANES) -> None:
        self.lanes = lanes
        self.waiting: deque[Request] = deque()

    def __len__(self) -> int:
        return len(self.waiting)

    def put(self, request: Request, first: bool = False) -> None:
        if first:
            self.waiting.appendleft(request)
        else:
            self.waiting.append(request)

    def take(self) -> list[Request]:
        """The next task: the oldest batch, with later batches of its kind while the task stays
        within `lanes` robots (a batch larger than that goes alone)."""
        head = self.waiting.popleft()
        task, robots = [head], len(head.files)
        if head.alone or head.kind in ("mixed", "?"):
            return task
        for request in list(self.waiting):
            if robots >= self.lanes:
                break
            fits = robots + len(request.files) <= self.lanes
            if fits and not request.alone and request.kind == head.kind:
                self.waiting.remove(request)
                task.append(request)
                robots += len(request.files)
        return task

    def remove(self, prefix: str) -> list[Request]:
        """Take out the batches whose key starts with `prefix`."""
        gone = [request for request in self.waiting if request.key.startswith(prefix)]
        for request in gone:
            self.waiting.remove(request)
        return gone


def task_files(task: Sequence[Request]) -> list[Any]:
    return [file for request in task for file in request.files]


def split_results(task: Sequence[Request], values: Sequence[float | None]) -> None:
    """Hand each batch of a finished task its own robots' results (in order)."""
    start = 0
    for request in task:
        stop = start + len(request.files)
        if not request.future.done():  # a dropped batch already has its answer
            request.future.set_result(list(values[start:stop]))
        start = stop
