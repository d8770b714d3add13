"""The in-process evaluators (`softevo.core.physics.evaluation`): the pool survives a killed
process."""

from __future__ import annotations

import numpy as np

from softevo.core.config import resolve
from softevo.core.physics.evaluation import PoolEvaluator, SerialEvaluator
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.search.evolution import Evolution
from tests.core.search.test_evolution import SMALL


def test_pool_rebuilds_itself_after_a_worker_process_is_killed() -> None:
    import os
    import signal

    evolution = Evolution.start(resolve({**SMALL, "seed": 3}))
    files = [robot_to_json(evolution.robot(item)) for item in evolution.individuals()]
    expected = SerialEvaluator().evaluate_batch(files).fitness
    with PoolEvaluator(2) as evaluator:
        assert np.array_equal(evaluator.evaluate_batch(files).fitness, expected, equal_nan=True)
        victim = next(iter(evaluator._pool._processes))  # a live pool process
        os.kill(victim, signal.SIGKILL)
        assert np.array_equal(evaluator.evaluate_batch(files).fitness, expected, equal_nan=True)
        assert victim not in evaluator._pool._processes
