"""The baselines of `StrategySettings.algorithm`: random search and a (1+lambda) hill climber."""

from __future__ import annotations

import json

import numpy as np
import pytest

from softevo.core.config import ConfigError, resolve
from softevo.core.search.configured import StrategyState
from tests.core.search.test_algorithm import Held, make, run, toy_fitness


@pytest.mark.parametrize("algorithm", ["random", "hillclimb"])
def test_seeded_like_the_ga(algorithm: str) -> None:
    assert run(make(1, algorithm=algorithm)) == run(make(1, algorithm=algorithm))
    assert run(make(1, algorithm=algorithm)) != run(make(2, algorithm=algorithm))


def test_random_search_draws_a_whole_new_population_every_generation() -> None:
    search = make(algorithm="random", immigrants=0.9)  # immigrants mean nothing here
    seen: set[tuple] = set()
    while not search.done:
        current = search.ask()
        assert all(item.operator == "random" and item.parents == () for item in current)
        genomes = {tuple(item.genome.discrete) for item in current}
        assert len(genomes & seen) <= 1  # independent draws (a repeat is possible, not likely)
        seen |= genomes
        search.tell(toy_fitness(current))


def test_hill_climber_keeps_the_best_and_mutates_it() -> None:
    climber = make(algorithm="hillclimb", mutation_genes=2)
    climber.tell(toy_fitness(climber.ask()))
    curve = []
    while not climber.done:
        previous = climber.state.previous
        fitness = np.asarray(climber.state.previous_fitness)
        best = previous[int(np.argmax(fitness))].genome
        current = climber.ask()
        assert current[0].genome == best and current[0].operator == "survivor"
        for item in current[1:]:
            assert item.operator == "copy+mutation"
            changed = np.count_nonzero(np.array(item.genome.discrete) != np.array(best.discrete))
            assert changed <= 2
        stats = climber.tell(toy_fitness(current))
        curve.append(stats.best_so_far)
    assert curve == sorted(curve)  # the climber never loses its best
    assert curve[-1] > curve[0]  # and on this landscape it climbs


def test_a_baseline_resumes_from_its_json_state() -> None:
    whole = make(algorithm="hillclimb")
    expected = run(whole)
    part = make(algorithm="hillclimb")
    for _ in range(5):
        part.tell(toy_fitness(part.ask()))
    state = StrategyState.from_json(json.loads(json.dumps(part.state.to_json())))
    resumed = Held(part.algorithm, state)
    assert run(resumed) == expected


def test_an_unknown_algorithm_is_refused_naming_the_field() -> None:
    with pytest.raises(ConfigError, match="algorithm"):
        resolve({"preset": "quick", "algorithm": "annealing"})
    assert resolve({"preset": "quick", "algorithm": "random"}).algorithm == "random"
