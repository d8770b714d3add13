"""Whole runs: reproducible to the last digit whatever the evaluator, and better than chance."""

from __future__ import annotations

import numpy as np
import pytest

from softevo.core.config import resolve
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import PoolEvaluator, SerialEvaluator
from softevo.core.robots.robot_file import robot_to_json

SMALL = {"preset": "quick", "generations": 6, "population": 10}


@pytest.fixture(scope="module")
def pool() -> PoolEvaluator:
    with PoolEvaluator(2) as evaluator:
        yield evaluator


def curve(request: dict, evaluator) -> list[dict]:
    evolution = Evolution.start(resolve(request))
    evolution.run(evaluator)
    return evolution.curve()


def test_same_seed_gives_identical_curves_serial_and_with_two_processes(pool) -> None:
    serial = curve({**SMALL, "seed": 11}, SerialEvaluator())
    parallel = curve({**SMALL, "seed": 11}, pool)
    assert serial == parallel  # every float equal, not approximately
    assert len(serial) == 6 and serial[0]["evaluations"] == 10


def test_different_seeds_give_different_curves() -> None:
    assert curve({**SMALL, "seed": 1}, SerialEvaluator()) != curve(
        {**SMALL, "seed": 2}, SerialEvaluator()
    )


def test_cache_saves_survivors_and_counts_add_up() -> None:
    evolution = Evolution.start(resolve({**SMALL, "seed": 3}))
    evolution.run(SerialEvaluator())
    rows = evolution.curve()
    assert rows[0]["saved"] == 0
    assert all(row["saved"] >= 5 for row in rows[1:])  # half of each group survives
    assert sum(r["evaluations"] for r in rows) == evolution.evaluations == len(evolution.cache)
    assert sum(r["evaluations"] + r["saved"] for r in rows) == 6 * 10


def test_a_robot_that_cannot_be_built_fails_with_nan_not_zero() -> None:
    document = robot_to_json(
        resolve(SMALL)
        .make_encoding()
        .to_robot(
            resolve(SMALL).make_encoding().genome(np.zeros(27, dtype=int), (0.0, 0.0, 0.0)),
            resolve(SMALL).sim,
        )
    )
    fitness = SerialEvaluator().evaluate_batch([document, {"format": "softevo.robot/1"}]).fitness
    assert np.isnan(fitness).all()


@pytest.mark.slow
def test_evolution_beats_random_search_on_the_same_budget(pool) -> None:
    """GA best / random best, measured 2026-12-07 (quick, physical profile): 1.55, 1.14, 1.22
    for seeds 0-2 (seeds 3-5 gave 1.79, 1.25 and 1.20; three keep the suite's time)."""
    ratios = []
    for seed in range(3):
        config = resolve({"preset": "quick", "seed": seed})
        evolution = Evolution.start(config)
        evolution.run(pool)
        encoding, rng = config.make_encoding(), np.random.default_rng([seed, 999])
        randoms = [
            robot_to_json(encoding.to_robot(encoding.random(rng), config.sim))
            for _ in range(evolution.evaluations)
        ]
        ratios.append(evolution.best_robot()[1] / np.nanmax(pool.evaluate_batch(randoms).fitness))
    assert np.mean(ratios) > 1.1, ratios
    assert all(r > 1 for r in ratios), ratios
