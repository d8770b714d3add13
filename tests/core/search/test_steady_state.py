"""Steady-state evolution: births told in birth order give one run whatever the workers, their
timing, a stop and a resume; the window bounds what is in flight."""

from __future__ import annotations

import itertools
import random
import threading
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
import pytest

from softevo.core.config import ConfigError, resolve
from softevo.core.evaluator import BatchResult, Evaluator
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import PoolEvaluator, SerialEvaluator
from softevo.core.search.state import StrategyState
from softevo.core.search.steady_state import KEY

REQUEST = {
    "preset": "quick",
    "seed": 4,
    "population": 8,
    "generations": 5,
    "algorithm": "steady-state",
    "options": {"window": 4},
}


def _run(evaluator: Evaluator, request: dict[str, Any] = REQUEST) -> Evolution:
    evolution = Evolution.start(resolve(request))
    evolution.run(evaluator)
    return evolution


class Shuffled(Evaluator):
    """The serial fitness, but each batch lands after a random delay (or in proportion to its
    robots' size, `by_size`) on up to `capacity` threads: results arrive in any order."""

    def __init__(self, capacity: int, seed: int, by_size: bool = False) -> None:
        self.serial, self.slots = SerialEvaluator(), capacity
        self.random, self.by_size, self.lock = random.Random(seed), by_size, threading.Lock()
        self.most = 0  # most robots out at once
        self.out = 0

    def evaluate_batch(self, robot_files: Sequence[dict[str, Any]], key: str | None = None):
        with self.lock:
            self.out += len(robot_files)
            self.most = max(self.most, self.out)
            delay = self.random.uniform(0, 0.03)
        if self.by_size:
            delay = 0.001 * sum(v != "empty" for file in robot_files for v in file["voxels"])
        result = self.serial.evaluate_batch(robot_files, key)
        time.sleep(delay)
        with self.lock:
            self.out -= len(robot_files)
        return BatchResult(result.fitness, "shuffled", result.seconds, result.measures)

    def capacity(self) -> int:
        return self.slots

    def close(self) -> None:
        pass


def test_the_curve_is_the_same_for_any_timing_and_worker_count() -> None:
    serial = _run(SerialEvaluator())
    curve = serial.curve()
    assert len(curve) == 5 and curve[-1]["best_so_far"] >= curve[0]["best_so_far"]
    assert sum(row["evaluations"] + row["saved"] for row in curve) == 8 * 5
    for capacity, seed in ((2, 1), (4, 2), (8, 3)):
        shuffled = Shuffled(capacity, seed)
        assert _run(shuffled).curve() == curve, (capacity, seed)
        assert shuffled.most <= 4  # never more than the window in flight
    assert _run(Shuffled(4, 0, by_size=True)).curve() == curve  # no bias to quick robots


def test_one_two_and_four_processes_give_the_same_run() -> None:
    serial = _run(SerialEvaluator())
    for processes in (2, 4):
        with PoolEvaluator(processes) as pool:
            pooled = _run(pool)
        assert pooled.curve() == serial.curve()
        assert pooled.state.to_json() == serial.state.to_json()


@pytest.mark.parametrize("window", [4, 12])  # 12: past the population (8)
def test_a_stop_and_resume_from_the_stored_state_goes_on_to_the_same_run(window: int) -> None:
    request = {**REQUEST, "options": {"window": window}}
    whole = _run(SerialEvaluator(), request)
    first = Evolution.start(resolve(request))
    evaluator = Shuffled(4, 7)
    for _ in range(2):
        first.step(evaluator)  # births of row 2 are still in flight when it stops
    assert len(first.state.data[KEY]["window"]) == window
    state = StrategyState.from_json(first.state.to_json())
    resumed = Evolution.resume(resolve(request), state, first.cache, measures=first.measures)
    resumed.run(SerialEvaluator())
    assert resumed.curve() == whole.curve()
    assert resumed.state.to_json() == whole.state.to_json()


def test_births_name_their_parents_by_birth_and_the_best_never_falls() -> None:
    evolution = _run(SerialEvaluator(), {**REQUEST, "generations": 6})
    curve = evolution.curve()
    assert all(a["best_so_far"] <= b["best_so_far"] for a, b in itertools.pairwise(curve))
    kept = evolution.state.data[KEY]
    assert kept["told"] == 8 * 6 and [item["n"] for item in kept["window"]] == [48, 49, 50, 51]
    assert len(kept["births"]) == 8 and max(kept["births"]) < 8 * 6
    population = np.asarray(evolution.state.previous_fitness)
    assert np.nanmax(population) == curve[-1]["best_so_far"]


def test_a_steady_state_map_elites_draws_parents_from_the_archive() -> None:
    request = {
        **REQUEST,
        "shape": [2, 2, 2],
        "descriptors": ["voxels", "actuated"],
        "bins": [4, 4],
        "options": {"window": 4, "parents": "archive"},
    }
    serial = _run(SerialEvaluator(), request)
    assert serial.curve() == _run(Shuffled(4, 5), request).curve()
    assert serial.curve()[-1]["coverage"] > 0
    other = _run(SerialEvaluator(), {**request, "options": {"window": 4}})
    assert other.curve() != serial.curve()  # the parents' source is honoured


def test_a_window_past_the_population_starts_with_that_many_random_births() -> None:
    """W > P: births 0 .. W-1 are random (nothing is told when they are bred), later ones bred;
    the run is still the same whatever order results land in."""
    request = {**REQUEST, "options": {"window": 20}}
    serial = _run(SerialEvaluator(), request)
    assert serial.curve() == _run(Shuffled(4, 7), request).curve()
    evolution, operators = Evolution.start(resolve(request)), []
    for _ in range(3):  # rows of 8 births: 0-7, 8-15, 16-23
        step = evolution.stepper.step(evolution.state, evolution.cache, SerialEvaluator())
        evolution.state = step.state
        operators += [individual.operator for individual in step.individuals]  # birth order
    assert set(operators[:20]) == {"random"}  # births 0-19: below W, random
    assert "random" not in operators[20:] and set(operators[20:]) - {"immigrant"}  # bred
    narrow = _run(SerialEvaluator(), {**REQUEST, "options": {"window": 8}})
    assert narrow.curve() != serial.curve()


@pytest.mark.parametrize(
    ("options", "extra", "message"),
    [
        ({"window": 0}, {}, "options.window"),
        ({"window": 65}, {}, "options.window: 65 is more than 8 populations (64)"),
        ({"parents": "archive"}, {}, 'options.parents: "archive" needs descriptors'),
        ({"parents": "elsewhere"}, {}, "options.parents"),
    ],
)
def test_bad_options_are_refused_by_name(
    options: dict[str, Any], extra: dict[str, Any], message: str
) -> None:
    with pytest.raises(
        (ConfigError, ValueError), match=message.replace("(", r"\(").replace(")", r"\)")
    ):
        resolve({**REQUEST, "options": options, **extra})


class Sizes(Shuffled):
    """Shuffled, noting how many robots each call held."""

    def __init__(self, capacity: int) -> None:
        super().__init__(capacity, 0)
        self.sizes: list[int] = []

    def evaluate_batch(self, robot_files: Sequence[dict[str, Any]], key: str | None = None):
        self.sizes.append(len(robot_files))
        return super().evaluate_batch(robot_files, key)


def test_robots_of_small_boxes_share_calls_up_to_the_lanes() -> None:
    """A paper-cube robot (8 lattice points) goes out 8 to a call in a streaming run, a 3x3x3
    voxel robot (64 points) `batch_size` (4) at most; the same run either way."""
    cube = {
        "preset": "paper-cube",
        "seed": 2,
        "generations": 3,
        "algorithm": "steady-state",
        "options": {"window": 60},
        "sim": {"duration": 1.0, "settle_time": 0.5},
    }
    sizes = Sizes(1)
    assert _run(sizes, cube).curve() == _run(SerialEvaluator(), cube).curve()
    assert max(sizes.sizes) == 8
    voxels = Sizes(1)
    _run(voxels, {**REQUEST, "options": {"window": 8}})
    assert max(voxels.sizes) == 4
