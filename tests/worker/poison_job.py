"""A job for the fault tests: the real one, except that a batch holding a robot file marked
`"poison": true` reports an error, as a job whose evaluation raised does."""

from __future__ import annotations

from typing import Any

from softevo.worker.jobs import evaluate_batch as real_evaluate_batch
from softevo.worker.jobs import push_result


def evaluate_batch(batch_key: str, robot_files: list[dict[str, Any]]) -> dict[str, Any]:
    if any(isinstance(f, dict) and f.get("poison") for f in robot_files):
        payload = {"error": "RuntimeError: poison", "worker": "poison", "seconds": 0.0}
        return push_result(batch_key, {**payload, "robots": len(robot_files)})
    return real_evaluate_batch(batch_key, robot_files)


def evaluate_batch_silently(batch_key: str, robot_files: list[dict[str, Any]]) -> dict[str, Any]:
    """Finishes without pushing a result for a marked batch (a lost result list, or a worker of
    another version whose result is skipped): RQ says finished, the result list stays empty."""
    if any(isinstance(f, dict) and f.get("poison") for f in robot_files):
        return {"lost": True}
    return real_evaluate_batch(batch_key, robot_files)


def stuck(batch_key: str, robot_files: list[dict[str, Any]]) -> dict[str, Any]:
    """Sleeps `robot_files[0]["sleep"]` s with SIGALRM blocked, as a numba loop holds off RQ's
    alarm, then reports each robot's speed as 1."""
    import signal
    import time

    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM})
    try:
        time.sleep(float(robot_files[0].get("sleep", 0)))
    finally:
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGALRM})
    payload = {"fitness": [1.0] * len(robot_files), "measures": [{}] * len(robot_files)}
    return push_result(batch_key, {**payload, "worker": "stuck", "seconds": 0.0})
