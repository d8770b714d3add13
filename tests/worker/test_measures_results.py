"""A worker's result carries every robot's record of measures beside its fitness; a result from a
worker of the release before records (a `heading` list) is still taken, as records of the heading
alone; one without either, or with records of the wrong shape, is malformed and never taken."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from softevo.core.evaluator import BatchResult
from softevo.worker.evaluator import parse_result

GOOD = {
    "fitness": [0.5, None, None],
    "measures": [{"speed": 0.5, "heading": -135.25, "energy": None}, {"stable": 0.0}, None],
    "seconds": 0.1,
    "worker": "w",
}


def test_a_result_with_records_is_taken_and_null_is_nan() -> None:
    payload = parse_result(json.dumps(GOOD), 3)
    assert payload is not None
    result = BatchResult.measured(payload, "w", 0.1)
    first, blown_up, unbuilt = result.records()
    assert first["speed"] == 0.5 and first["heading"] == -135.25 and math.isnan(first["energy"])
    assert blown_up == {"stable": 0.0} and unbuilt == {} and math.isnan(result.fitness[1])


def test_an_older_workers_headings_become_records_of_the_heading() -> None:
    older = {"fitness": [0.5, None], "heading": [-135.25, None], "seconds": 0.1, "worker": "w"}
    payload = parse_result(json.dumps(older), 2)
    assert payload is not None
    first, failed = BatchResult.measured(payload, "w", 0.1).records()
    assert first == {"heading": -135.25} and set(failed) == {"heading"}
    assert math.isnan(failed["heading"])


@pytest.mark.parametrize(
    "change",
    [{"measures": None}, {"measures": [{}]}, {"measures": [{"speed": "fast"}, None, None]},
     {"measures": [[0.5], None, None]}, {"measures": "{}"}],
    ids=["missing", "short", "not-a-number", "not-an-object", "not-a-list"],
)  # fmt: skip
def test_a_result_without_well_formed_records_is_malformed(change: dict) -> None:
    payload = {**GOOD, **change}
    if change.get("measures") is None:
        payload.pop("measures")
    assert parse_result(json.dumps(payload), 3) is None


def test_a_batch_result_without_records_has_an_empty_one_each() -> None:
    result = BatchResult(np.array([0.1, 0.2]), "w", 0.0)
    assert result.records() == [{}, {}]
