"""A worker's result carries every robot's record of measures beside its fitness; a result from a
worker of the release before records (a `heading` list) is still taken, as records of the heading
alone; one without either, or with records of the wrong shape, is malformed and never taken."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from softevo.api.store.fitness_rows import measures_text
from softevo.core.evaluator import BatchResult
from softevo.core.nulls import record_text
from softevo.worker.results import parse_result

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


def test_each_records_text_is_kept_as_it_came_and_stored_as_it_is() -> None:
    """The job sends each record's text beside it: the service writes that text, not one of
    its own (it encodes a record only when no text came, from a worker of the release before)."""
    texts = [record_text(GOOD["measures"][0]), record_text(GOOD["measures"][1]), None]
    assert texts[0] == '{"speed":0.5,"heading":-135.25,"energy":null}'
    payload = parse_result(json.dumps({**GOOD, "texts": texts}), 3)
    assert payload is not None
    first, blown_up, unbuilt = BatchResult.measured(payload, "w", 0.1).records()
    assert first.text == texts[0] and measures_text(first) == texts[0]
    assert measures_text(blown_up) == '{"stable":0.0}' and measures_text(unbuilt) == "{}"
    older = BatchResult.measured(parse_result(json.dumps(GOOD), 3), "w", 0.1).records()[0]
    assert measures_text(older) == texts[0]  # encoded here: the same text


@pytest.mark.parametrize(
    "texts",
    [
        ['{"speed":0.5,"heading":-135.25,"energy":0.0}', None, None],
        ['{"speed":0.5,"heading":-135.25}', None, None],
        ['{"speed":0.5,"heading":-135.25,"energy":NaN}', None, None],
        ["speed", None, None],
        [None, None, "{}"],
        [{"speed": 0.5}, None, None],
        [None, None],
        "[]",
    ],
    ids=[
        "another-value",
        "a-measure-short",
        "nan",
        "not-json",
        "for-no-record",
        "not-a-text",
        "short",
        "not-a-list",
    ],
)
def test_a_result_whose_texts_are_not_its_records_is_malformed(texts: object) -> None:
    assert parse_result(json.dumps({**GOOD, "texts": texts}), 3) is None


def test_an_older_workers_headings_become_records_of_the_heading() -> None:
    older = {"fitness": [0.5, None], "heading": [-135.25, None], "seconds": 0.1, "worker": "w"}
    payload = parse_result(json.dumps(older), 2)
    assert payload is not None
    first, failed = BatchResult.measured(payload, "w", 0.1).records()
    assert first == {"heading": -135.25} and set(failed) == {"heading"}
    assert math.isnan(failed["heading"])


@pytest.mark.parametrize(
    "change",
    [
        {"measures": None},
        {"measures": [{}]},
        {"measures": [{"speed": "fast"}, None, None]},
        {"measures": [[0.5], None, None]},
        {"measures": "{}"},
    ],
    ids=["missing", "short", "not-a-number", "not-an-object", "not-a-list"],
)
def test_a_result_without_well_formed_records_is_malformed(change: dict) -> None:
    payload = {**GOOD, **change}
    if change.get("measures") is None:
        payload.pop("measures")
    assert parse_result(json.dumps(payload), 3) is None


def test_a_batch_result_without_records_has_an_empty_one_each() -> None:
    result = BatchResult(np.array([0.1, 0.2]), "w", 0.0)
    assert result.records() == [{}, {}]
