"""The stand-in job of `bench/scaling.py`: what `softevo.worker.jobs.evaluate_batch` does, with
the simulation replaced by a sleep of the batch's measured simulation time, so that 32 workers
on a two-core machine cost (almost) no CPU.

The sleep comes from a time model measured on this machine (`SOFTEVO_SCALING_MODEL`, JSON): the
seconds per occupied voxel a robot costs in a kernel call of n robots (n = 1, 2, 3, 4; the
kernel's SIMD lanes make a robot cheaper in a fuller call), times the batch's occupied voxels.
The fitness is a deterministic function of the robot (its share of actuated voxels, as
`bench/coordinator.py`'s stand-in), so the run selects and converges, and its duplicates are
found and not sent, as a real run's are; each robot has a record of measures (and its JSON
text, where the real job sends one), as a real job's. Only this module is imported by the
workers: no physics, no kernels.
"""

from __future__ import annotations

import json
import os
import socket
import time
from functools import cache
from typing import Any

from coordinator import job_output
from rq import get_current_job

from softevo.core import nulls
from softevo.worker.jobs import push_result

#: The environment variable holding the time model (`model_json`).
MODEL_ENV = "SOFTEVO_SCALING_MODEL"
#: The job function's import path, as the workers are told to allow it.
FUNCTION = "scaling_job.sleep_batch"
#: How the real job writes a record of measures as text, where it sends that text too.
RECORD_TEXT = getattr(nulls, "record_text", None)


def occupied(robot_file: dict[str, Any]) -> int:
    """The robot's occupied voxels (what its springs and masses grow with)."""
    return sum(label != "empty" for label in robot_file["voxels"])


def surrogate(robot_file: dict[str, Any]) -> float:
    """The stand-in's fitness: the share of the box's voxels that are actuated."""
    labels = robot_file["voxels"]
    return (labels.count("sine") + labels.count("neg_sine")) / len(labels)


def model_json(per_voxel: dict[int, float]) -> str:
    """The time model as the workers read it: kernel-call width -> seconds per occupied voxel."""
    return json.dumps({str(width): seconds for width, seconds in per_voxel.items()})


@cache
def _model() -> dict[int, float]:
    return {int(width): float(s) for width, s in json.loads(os.environ[MODEL_ENV]).items()}


def batch_seconds(robot_files: list[dict[str, Any]], per_voxel: dict[int, float]) -> float:
    """The batch's simulation time by the model: one kernel call of all its robots (a width
    past the widest measured costs what that one does per voxel)."""
    width = min(len(robot_files), max(per_voxel))
    return per_voxel[width] * sum(map(occupied, robot_files))


def sleep_batch(batch_key: str, robot_files: list[dict[str, Any]]) -> dict[str, Any]:
    """A batch job: sleep the batch's simulation time, push fitness and measures as the real
    job does. `seconds` is the modelled simulation time (the busy time a real worker would
    have), not the sleep as the scheduler stretched it; `started` when the sleep began (unix
    time, this machine's clock), for the bench's busy fraction in mid-run."""
    seconds, started = batch_seconds(robot_files, _model()), time.time()
    time.sleep(seconds)
    job = get_current_job()
    worker = (job and job.worker_name) or f"{socket.gethostname()}:{os.getpid()}"
    payload: dict[str, Any] = dict(job_output([surrogate(f) for f in robot_files], "measures"))
    if RECORD_TEXT is not None:  # a tree whose job sends each record's JSON text: so does this
        payload["texts"] = [RECORD_TEXT(record) for record in payload["measures"]]
    payload.update(worker=worker, seconds=seconds, robots=len(robot_files), started=started)
    return push_result(batch_key, payload)
