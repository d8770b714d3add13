"""The jobs an RQ worker runs: a batch of robot files in, fitness and measures out, pushed onto
the batch's result list (`softevo.worker.queue.result_key`) so the coordinator wakes at once; and
a replay of one robot (its frames), pushed the same way. Plain JSON both ways.

A robot that cannot be built or whose simulation blows up has fitness None (NaN): failed, never
0. Anything else that goes wrong is reported as `error`, and the evaluator retries the robots one
by one, so one bad robot fails alone.
"""

from __future__ import annotations

import os
import socket
import time
from typing import Any

from rq import get_current_job

from softevo.worker import queue


def evaluate_batch(batch_key: str, robot_files: list[dict[str, Any]]) -> dict[str, Any]:
    from softevo.core.physics.evaluation import (
        evaluate_robot_files,  # loaded (and warm) in the worker
    )

    started = time.perf_counter()
    job = get_current_job()  # the worker's name is on the job for every worker class
    worker = (job and job.worker_name) or f"{socket.gethostname()}:{os.getpid()}"
    try:
        payload: dict[str, Any] = dict(evaluate_robot_files(robot_files))
    except Exception as error:
        payload = {"error": f"{type(error).__name__}: {error}"[:1000]}
    payload.update(worker=worker, seconds=time.perf_counter() - started, robots=len(robot_files))
    return push_result(batch_key, payload)


def replay(
    batch_key: str, robot_files: list[dict[str, Any]], fps: float, max_positions: int
) -> dict[str, Any]:
    """A replay job: the one robot of `robot_files` simulated with its frames recorded
    (`softevo.core.outputs.replay`), pushed like a batch's result with its speed as the fitness."""
    from softevo.core.outputs.replay import replay_frames
    from softevo.core.robots.robot_file import RobotFileError, parse_robot

    started = time.perf_counter()
    job = get_current_job()
    worker = (job and job.worker_name) or f"{socket.gethostname()}:{os.getpid()}"
    try:
        (document,) = robot_files
        data = replay_frames(parse_robot(document), float(fps), int(max_positions))
        payload: dict[str, Any] = {"fitness": [data["speed"]], "measures": [None], "replay": data}
    except (RobotFileError, ValueError, TypeError) as error:
        payload = {"error": f"{type(error).__name__}: {error}"[:1000]}
    payload.update(worker=worker, seconds=time.perf_counter() - started, robots=1)
    return push_result(batch_key, payload)


def push_result(batch_key: str, payload: dict[str, Any]) -> dict[str, Any]:
    """Push `payload` onto the batch's result list (inside an RQ job) and return it."""
    job = get_current_job()
    if job is not None:
        payload["job"] = job.id
        queue.push_result(job.connection, batch_key, payload)
    return payload
