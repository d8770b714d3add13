"""The ask/tell algorithm: determinism, elitism, immigrants, NaN handling, JSON state."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

from softevo.core.config import resolve
from softevo.core.robots.encoding_registry import make_encoding
from softevo.core.search.configured import Strategy, StrategySettings, StrategyState, make_strategy
from softevo.core.search.stats import GenerationStats


def toy_fitness(individuals: list) -> np.ndarray:
    """A cheap deterministic stand-in for simulation: how many voxels are `hard` (label 2)."""
    return np.array([sum(g == 2 for g in ind.genome.discrete) / 10 for ind in individuals])


class Held:
    """The pure algorithm with its state held here, as a driver holds it."""

    def __init__(self, algorithm: Strategy, state: StrategyState) -> None:
        self.algorithm, self.state = algorithm, state
        self.config, self.encoding = algorithm.config, algorithm.encoding

    @property
    def done(self) -> bool:
        return self.algorithm.done(self.state)

    def ask(self) -> list:
        return self.algorithm.ask(self.state)

    def tell(self, fitness: object) -> GenerationStats:
        self.state, stats = self.algorithm.tell(self.state, self.ask(), fitness)
        return stats


def make(seed: int = 1, **changes: object) -> Held:
    config = StrategySettings.model_validate({"population": 12, "generations": 15, **changes})
    algorithm = make_strategy(config, make_encoding("voxel", (3, 3, 2)))
    return Held(algorithm, algorithm.start(seed))


def run(algorithm: Held) -> list[float]:
    while not algorithm.done:
        algorithm.tell(toy_fitness(algorithm.ask()))
    return [stats.best_so_far for stats in algorithm.state.history]


def test_same_seed_same_run_and_other_seed_differs() -> None:
    first, second, other = make(seed=1), make(seed=1), make(seed=2)
    assert run(first) == run(second)
    assert first.state.to_json() == second.state.to_json()
    run(other)
    assert other.state.to_json()["history"] != first.state.to_json()["history"]


@pytest.mark.parametrize("selection", ["grouped", "tournament", "roulette"])
def test_elitism_keeps_the_best_individual_and_the_curve_from_falling(selection: str) -> None:
    algorithm = make(selection=selection, mutation_probability=0.5)
    previous_best = None
    while not algorithm.done:
        individuals = algorithm.ask()
        if previous_best is not None:
            assert previous_best in {i.genome for i in individuals}
        fitness = toy_fitness(individuals)
        algorithm.tell(fitness)
        previous_best = individuals[int(np.argmax(fitness))].genome
    curve = [stats.best_so_far for stats in algorithm.state.history]
    assert all(later >= earlier for earlier, later in itertools.pairwise(curve))


def test_without_elitism_tournament_can_lose_the_best() -> None:
    algorithm = make(selection="tournament", elitism=False, mutation_probability=1.0)
    lost = 0
    while not algorithm.done:
        individuals = algorithm.ask()
        fitness = toy_fitness(individuals)
        bests = [stats.best for stats in algorithm.state.history]
        lost += bool(bests) and float(fitness.max()) < bests[-1]
        algorithm.tell(fitness)
    assert lost > 0  # so the elitism test above tests something


def test_generation_can_be_regenerated_from_seed_and_previous_population() -> None:
    algorithm = make(seed=7)
    for _ in range(4):
        algorithm.tell(toy_fitness(algorithm.ask()))
    upcoming = algorithm.ask()
    # A fresh algorithm given only the stored generation g-1 and its fitness breeds the same g.
    state = algorithm.state
    rebuilt = StrategyState(
        seed=7,
        generation=state.generation,
        previous=state.previous,
        previous_fitness=state.previous_fitness,
    )
    again = make_strategy(algorithm.config, algorithm.encoding).ask(rebuilt)
    assert [i.genome for i in again] == [i.genome for i in upcoming]
    assert [i.operator for i in again] == [i.operator for i in upcoming]


def test_state_round_trips_through_json_and_resumes_identically() -> None:
    whole = make(seed=3)
    run(whole)
    interrupted = make(seed=3)
    for _ in range(6):
        interrupted.tell(toy_fitness(interrupted.ask()))
    text = json.dumps(interrupted.state.to_json(), allow_nan=False)
    resumed = Held(interrupted.algorithm, StrategyState.from_json(json.loads(text)))
    run(resumed)
    assert resumed.state.to_json() == whole.state.to_json()


def test_immigrants_are_new_and_survivors_are_kept() -> None:
    algorithm = make(seed=5, immigrants=0.25, groups=3, survival=0.5)
    previous = algorithm.ask()
    algorithm.tell(toy_fitness(previous))
    current = algorithm.ask()
    immigrants = [i for i in current if i.operator == "immigrant"]
    survivors = [i for i in current if i.operator == "survivor"]
    assert len(immigrants) == 3  # 0.25 * 12
    old = {i.genome for i in previous}
    assert all(i.genome not in old for i in immigrants)
    assert len(survivors) == 6  # half of each of 3 groups of 4
    assert all(previous[s.parents[0]].genome == s.genome for s in survivors)
    assert len(current) == 12


def test_failed_individuals_rank_last_and_are_reported() -> None:
    algorithm = make(seed=2, population=10, groups=1, survival=0.3)
    individuals = algorithm.ask()
    fitness = np.full(10, math.nan)
    fitness[4] = 0.0  # a real (if poor) score beats every failure
    stats = algorithm.tell(fitness)
    assert stats.failed == 9 and stats.best == 0.0 and stats.mean == 0.0
    survivors = [i for i in algorithm.ask() if i.operator == "survivor"]
    assert survivors[0].genome == individuals[4].genome
    state = json.loads(json.dumps(algorithm.state.to_json(), allow_nan=False))
    assert state["previous_fitness"].count(None) == 9


def test_diversity_falls_when_the_population_converges() -> None:
    algorithm = make(seed=4, immigrants=0.0, mutation_probability=0.0, generations=25)
    run(algorithm)
    history = algorithm.state.history
    assert history[0].diversity > 0.6  # random labels: about 1 - 1/5
    assert history[-1].diversity < history[0].diversity / 2


def test_tell_refuses_the_wrong_number_of_values() -> None:
    algorithm = make()
    with pytest.raises(ValueError, match="expected 12 fitness values"):
        algorithm.tell([1.0, 2.0])


def test_presets_resolve_with_the_papers_numbers() -> None:
    cube = resolve({"preset": "paper-cube"})
    assert (cube.population, cube.groups, cube.survival) == (30, 3, 0.2)
    assert cube.crossover_probability == pytest.approx(24 / 30)
    assert (cube.mutation_probability, cube.mutation_genes) == (0.2, 2)
    voxel = resolve({"preset": "paper-voxel", "shape": [5, 5, 3], "seed": 9})
    assert (voxel.population, voxel.generations, voxel.survival) == (25, 100, 0.5)
    assert (voxel.mutation_probability, voxel.immigrants, voxel.shape) == (0.02, 0.12, (5, 5, 3))
    assert voxel.sim.dt == 0.0005 and voxel.sim.damping == 0.99


def test_voxel_plus_is_paper_voxel_with_more_mutation() -> None:
    paper = resolve({"preset": "paper-voxel"}).to_json()
    plus = resolve({"preset": "voxel-plus"}).to_json()
    differing = {key for key in paper if paper[key] != plus[key]}
    assert differing == {"preset", "mutation_probability"}
    assert plus["mutation_probability"] == 0.5


def test_ask_and_tell_are_pure() -> None:
    """Neither changes the state it is given: the holder decides when the next one is current."""
    held = make(seed=9)
    held.tell(toy_fitness(held.ask()))
    before = json.dumps(held.state.to_json())
    individuals = held.algorithm.ask(held.state)
    assert held.algorithm.ask(held.state) == individuals  # the same generation every time
    following, stats = held.algorithm.tell(held.state, individuals, toy_fitness(individuals))
    assert json.dumps(held.state.to_json()) == before
    assert following.generation == held.state.generation + 1 == stats.generation + 1
    assert following.history[:-1] == held.state.history and following.history[-1] == stats
