"""A worker's result carries every robot's heading beside its fitness; one without it, or with
headings of the wrong shape, is malformed and never taken for a result."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from softevo.core.evaluator import BatchResult
from softevo.worker.evaluator import parse_result

GOOD = {"fitness": [0.5, None], "heading": [-135.25, None], "seconds": 0.1, "worker": "w"}


def test_a_result_with_headings_is_taken_and_a_failed_robot_has_nan() -> None:
    payload = parse_result(json.dumps(GOOD), 2)
    assert payload is not None
    result = BatchResult.measured(payload, "w", 0.1)
    assert result.heading is not None and result.heading[0] == -135.25
    assert math.isnan(result.heading[1]) and math.isnan(result.fitness[1])


@pytest.mark.parametrize(
    "change",
    [{"heading": None}, {"heading": [1.0]}, {"heading": ["north", 1.0]}, {"heading": "90"}],
    ids=["missing", "short", "not-a-number", "not-a-list"],
)
def test_a_result_without_well_formed_headings_is_malformed(change: dict) -> None:
    payload = {**GOOD, **change}
    if change.get("heading") is None:
        payload.pop("heading")
    assert parse_result(json.dumps(payload), 2) is None


def test_a_batch_result_without_headings_says_nan_for_each() -> None:
    result = BatchResult(np.array([0.1, 0.2]), "w", 0.0)
    assert np.isnan(result.headings()).all() and len(result.headings()) == 2
