"""One real worker on a private Redis evaluates a batch exactly like the serial evaluator."""

from __future__ import annotations

import numpy as np
import pytest

from core.config import resolve
from core.evaluation import SerialEvaluator
from core.evolution import Evolution
from core.robot_file import robot_to_json
from worker.evaluator import RQEvaluator

pytestmark = pytest.mark.redis


def test_rq_evaluator_matches_the_serial_one(redis_server, workers) -> None:
    workers.start("one")
    workers.wait_ready("one")
    evolution = Evolution.start(resolve({"preset": "quick", "population": 6, "seed": 2}))
    files = [robot_to_json(evolution.robot(item)) for item in evolution.algorithm.ask()]
    evaluator = RQEvaluator(redis_server.url)
    try:
        result = evaluator.evaluate_batch(files, key="smoke")
    finally:
        evaluator.close()
    assert np.array_equal(result.fitness, SerialEvaluator().evaluate(files), equal_nan=True)
    assert result.worker == "one" and result.seconds > 0
