"""The curve's `normalised_hypervolume` (issue 51): each objective scaled from its reference (0)
to its ideal (1), computed every generation beside the raw `hypervolume`, checked on a front
worked out by hand."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from softevo.core.robots.encoding_registry import make_encoding
from softevo.core.search import pareto
from softevo.core.search.configured import StrategySettings, make_strategy
from softevo.core.search.stats import GenerationStats, curve_columns

OBJECTIVES = [
    {"measure": "speed", "ideal": 0.5},  # reference 0 m/s (the default)
    {"measure": "cost_of_transport", "goal": "min", "reference": 100, "ideal": 0},
]
RECORDS = [
    {"speed": 0.5, "cost_of_transport": 50.0},  # scaled (1, 0.5)
    {"speed": 0.25, "cost_of_transport": 0.0},  # scaled (0.5, 1)
    {"speed": 0.75, "cost_of_transport": 100.0},  # past the ideal: (1, 0), on the front
    {"speed": math.nan, "cost_of_transport": math.nan},  # failed: counts for nothing
]


def told(records: list[dict[str, float]]) -> GenerationStats:
    """The curve row of one generation of random search told `records` (fitness = speed)."""
    config = StrategySettings.model_validate(
        {
            "algorithm": "random",
            "population": len(records),
            "generations": 2,
            "objectives": OBJECTIVES,
        }
    )
    strategy = make_strategy(config, make_encoding("voxel", (2, 2, 2)))
    state = strategy.start(1)
    individuals = strategy.ask(state)
    fitness = [record["speed"] for record in records]
    return strategy.tell(state, individuals, fitness, measures=records)[1]


def test_the_normalised_hypervolume_of_a_front_worked_out_by_hand() -> None:
    row = told(RECORDS)
    assert row.front_size == 3
    # raw, against (0 m/s, 100): the third point equals the reference in cost and spans nothing
    assert row.hypervolume == pytest.approx(0.5 * 50 + 0.25 * 50, rel=1e-12)
    # scaled, against (-0.1, -0.1): the boxes of (1.1, 0.6) and (0.6, 1.1), over 1.1 x 1.1
    by_hand = (1.1 * 0.6 + 0.6 * 0.5) / 1.21
    assert row.normalised_hypervolume == pytest.approx(by_hand, rel=1e-12)
    ideal = told([{"speed": 0.6, "cost_of_transport": 0.0}] * 2)
    assert ideal.normalised_hypervolume == pytest.approx(1.0, rel=1e-12)  # holds the ideal point
    failed = told([{"speed": math.nan, "cost_of_transport": math.nan}] * 2)
    assert failed.normalised_hypervolume == 0.0 and failed.front_size == 0


def test_the_column_is_a_pareto_column_and_an_old_row_reads_without_it() -> None:
    assert curve_columns(False, True)[-3:] == (
        "hypervolume",
        "front_size",
        "normalised_hypervolume",
    )
    old = {
        "generation": 0,
        "best": 0.1,
        "mean": 0.1,
        "median": 0.1,
        "min": 0.1,
        "std": 0.0,
        "best_so_far": 0.1,
        "diversity": 0.5,
        "size": 2,
        "failed": 0,
        "hypervolume": 3.0,
        "front_size": 1,
    }
    stats = GenerationStats.from_json(old)
    assert stats.normalised_hypervolume is None
    assert "normalised_hypervolume" not in stats.to_json()
    assert told(RECORDS).to_json()["normalised_hypervolume"] > 0


def test_bounds_a_hair_apart_neither_overflow_nor_change_the_volume() -> None:
    values = np.array([[1.0, -1.0], [-1e300, 0.5], [0.5, math.nan]])
    ideal, nadir = np.array([5e-324, 1.0]), np.array([0.0, -2.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow warning either
        scaled = pareto.normalised_hypervolume(values, ideal, nadir)
    # the first row clipped to the ideal in speed, (-1 + 2) / 3 in cost; the second far past
    # the reference in speed counts for nothing, as the third (failed) does
    assert scaled == pytest.approx((1.1 * (1 / 3 + 0.1)) / 1.21, rel=1e-12)
