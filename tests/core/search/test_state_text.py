"""The GA state's fast JSON text (what the service stores every generation) parses to exactly
its `to_json`, for every algorithm and encoding, with failed robots and an archive."""

from __future__ import annotations

import json

import numpy as np
import pytest

from softevo.core.config import resolve
from softevo.core.search.configured import make_strategy
from softevo.core.search.state import StrategyState

CASES = [
    {"preset": "paper-voxel", "shape": [3, 3, 3]},
    {"preset": "paper-cube"},
    {"preset": "quick", "encoding": "voxel-phase"},
    {"preset": "quick", "encoding": "spring"},
    {"preset": "quick", "algorithm": "hillclimb"},
    {
        "preset": "quick",
        "algorithm": "map-elites",
        "descriptors": ["voxels", "soft"],
        "bins": [3, 4],
    },
]


@pytest.mark.parametrize("request_", CASES, ids=lambda case: "-".join(map(str, case.values())))
def test_the_state_text_parses_to_its_json(request_: dict) -> None:
    config = resolve({**request_, "seed": 5})
    algorithm = make_strategy(config.strategy_settings(), config.make_encoding())
    state = algorithm.start(5)
    rng = np.random.default_rng(0)
    checked = 0
    for generation in range(4):
        for history in (True, False):
            text = state.to_text(history)
            assert json.loads(text) == json.loads(json.dumps(state.to_json(history)))
            assert StrategyState.from_json(json.loads(text)).to_json(history) == state.to_json(
                history
            )
            checked += 1
        individuals = algorithm.ask(state)
        fitness = rng.random(len(individuals))
        fitness[generation % len(fitness)] = np.nan  # a failed robot: null in both
        state, _ = algorithm.tell(
            state, individuals, fitness, evaluations=len(individuals), saved=0
        )
    assert checked == 8
    if config.algorithm == "map-elites":
        assert state.archive is not None and state.archive.elites


def test_a_state_stored_with_its_next_generation_bred_goes_on_the_same() -> None:
    """States written before births were kept with the store held the next generation as
    `current`: it is bred again from the seed and `previous`, so it is read past."""
    config = resolve({"preset": "quick", "population": 6, "generations": 3, "seed": 2})
    algorithm = make_strategy(config.strategy_settings(), config.make_encoding())
    first = algorithm.ask(algorithm.start(2))
    state, _ = algorithm.tell(algorithm.start(2), first, np.arange(6.0))
    bred = algorithm.ask(state)
    old = {**state.to_json(), "current": [item.to_json() for item in bred]}
    loaded = StrategyState.from_json(old)
    assert "current" not in loaded.to_json() and algorithm.ask(loaded) == bred
