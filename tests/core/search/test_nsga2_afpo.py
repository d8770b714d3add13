"""NSGA-II and AFPO (issue 36): determinism, resume from JSON, selection on hand-made cases,
the front so far and its hypervolume, on synthetic records of measures."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from softevo.core.robots.encoding_registry import make_encoding
from softevo.core.search import pareto
from softevo.core.search.configured import StrategySettings, StrategyState, make_strategy
from softevo.core.search.state import Individual
from softevo.core.search.vectors import ideal_point, objective_values, reference_point

OBJECTIVES = ["speed", "-cost_of_transport"]


def toy_measures(individuals: list[Individual]) -> list[dict[str, float]]:
    """Two objectives that conflict: hard voxels (label 2) are fast, any material costs."""
    records = []
    for item in individuals:
        genes = np.array(item.genome.discrete)
        records.append(
            {
                "speed": float(np.count_nonzero(genes == 2)) / 10,
                "cost_of_transport": 1.0 + float(np.count_nonzero(genes)) / 10,
            }
        )
    return records


class Run:
    """A strategy with its state held here, told toy measures (fitness = speed)."""

    def __init__(self, seed: int = 1, **changes: object) -> None:
        config = StrategySettings.model_validate(
            {"population": 12, "generations": 10, "objectives": OBJECTIVES, **changes}
        )
        self.strategy = make_strategy(config, make_encoding("voxel", (3, 3, 2)))
        self.state = self.strategy.start(seed)
        self.told: list[dict[str, float]] = []

    def step(self) -> None:
        individuals = self.strategy.ask(self.state)
        records = toy_measures(individuals)
        self.told += records
        fitness = [record["speed"] for record in records]
        self.state, _ = self.strategy.tell(self.state, individuals, fitness, measures=records)

    def finish(self) -> list[dict]:
        while not self.strategy.done(self.state):
            self.step()
        return [stats.to_json() for stats in self.state.history]


@pytest.mark.parametrize("algorithm", ["nsga2", "afpo"])
def test_same_seed_same_run_and_resumed_from_json_the_same(algorithm: str) -> None:
    whole = Run(1, algorithm=algorithm)
    curve = whole.finish()
    assert Run(1, algorithm=algorithm).finish() == curve
    assert Run(2, algorithm=algorithm).finish() != curve
    part = Run(1, algorithm=algorithm)
    for _ in range(4):
        part.step()
    part.state = StrategyState.from_json(json.loads(part.state.to_text()))
    assert part.finish() == curve
    assert part.state.to_json() == whole.state.to_json()


@pytest.mark.parametrize("algorithm", ["nsga2", "afpo", "ga", "random"])
def test_curve_rows_carry_the_front_so_far_and_its_hypervolume(algorithm: str) -> None:
    run = Run(3, algorithm=algorithm)
    run.finish()
    config = run.strategy.config
    values = objective_values(config.objectives, run.told, np.array([r["speed"] for r in run.told]))
    front = np.unique(values[pareto.nondominated_mask(values)], axis=0)
    last = run.state.history[-1]
    assert last.front_size == len(front) > 1
    assert last.hypervolume == pytest.approx(
        pareto.hypervolume(values, reference_point(config.objectives)), rel=1e-12
    )
    volumes = [stats.hypervolume for stats in run.state.history]
    assert volumes == sorted(volumes) and volumes[-1] > volumes[0]
    specs = config.objectives
    scaled = pareto.normalised_hypervolume(values, ideal_point(specs), reference_point(specs))
    assert last.normalised_hypervolume == pytest.approx(scaled, rel=1e-12) and 0 < scaled < 1


def test_runs_without_objectives_keep_their_columns() -> None:
    run = Run(1, algorithm="ga", objectives=[])
    row = run.finish()[-1]
    assert "hypervolume" not in row and "front_size" not in row
    assert "normalised_hypervolume" not in row
    assert run.state.data is None


def held(strategy_name: str, population: int, values: list[list[float]], **data: list) -> tuple:
    """A strategy and a state as if `values` (maximised, NaN failed) had just been told."""
    config = StrategySettings.model_validate(
        {"algorithm": strategy_name, "population": population, "generations": 5}
    )
    strategy = make_strategy(config, make_encoding("voxel", (2, 2, 2)))
    rng = np.random.default_rng(0)
    previous = [Individual(strategy.encoding.random(rng), "random") for _ in values]
    born = data.pop("born", [[0, i] for i in range(len(values))])
    state = StrategyState(
        seed=0,
        generation=3,
        previous=previous,
        previous_fitness=[v[0] for v in values],
        data={
            "values": [[None if math.isnan(x) else x for x in v] for v in values],
            "born": born,
            **data,
        },
    )
    return strategy, state


def test_nsga2_keeps_the_front_then_the_lonelier_then_the_older() -> None:
    nan = math.nan
    values = [[0.2, 0.2], [1, 0], [nan, nan], [0.5, 0.5], [0, 1], [0.4, 0.6], [0.5, 0.5]]
    born = [[0, 0], [0, 1], [0, 2], [2, 3], [0, 4], [0, 5], [1, 6]]
    strategy, state = held("nsga2", 8, values, born=born)  # survivors: 4 of 8
    asked = strategy.ask(state)
    survivors = [item.parents[0] for item in asked if item.operator == "survivor"]
    # front {1, 3, 4, 5, 6}: the ends 1 and 4 (infinite crowding, the older first), then 5
    # (crowding 1.0), then of the copies 3 and 6 (crowding 0.6 each) the older, 6
    assert survivors == [1, 4, 5, 6]
    children = asked[4:]
    assert len(children) == 4 and all(set(c.parents) <= set(survivors) for c in children)


def test_afpo_keeps_the_young_beside_the_fit_and_adds_one_newcomer() -> None:
    values = [[1.0], [0.5], [0.1], [0.05], [0.3], [0.2]]
    founded = [0, 0, 3, 1, 0, 2]  # at generation 3: ages 3, 3, 0, 2, 3, 1
    strategy, state = held("afpo", 6, values, founded=founded)
    asked = strategy.ask(state)
    survivors = [item.parents[0] for item in asked if item.operator == "survivor"]
    # (age, fitness) layers: {0 (age 3, 1.0), 2 (age 0, 0.1), 5 (age 1, 0.2)} first: 3 kept,
    # filled by fitness: 0, 5, 2
    assert survivors == [0, 5, 2]
    assert [item.operator for item in asked[3:]] == ["copy+mutation"] * 2 + ["immigrant"]
    assert [item.parents for item in asked[3:5]] == [(0,), (5,)]
    following, _ = strategy.tell(state, asked, [0.0] * 6)
    assert following.data["founded"] == [0, 2, 3, 0, 2, 3]  # lineages kept; the newcomer's now
    assert following.data["born"][:3] == [[0, 0], [0, 5], [0, 2]]


def test_afpo_needs_room_for_a_child_and_a_newcomer() -> None:
    with pytest.raises(ValueError, match="population: afpo needs at least 3"):
        StrategySettings.model_validate({"algorithm": "afpo", "population": 2})


def test_a_state_without_the_strategy_data_is_refused_in_one_line() -> None:
    strategy, state = held("nsga2", 4, [[1.0], [0.0]])
    state.data = {"front": []}
    with pytest.raises(ValueError, match="state data: values and born are missing"):
        strategy.ask(state)


def test_a_weighted_ga_selects_on_the_weighted_sum_and_keeps_speed_as_fitness() -> None:
    # weight 1 on speed, 0 on cost: selection ranks what the plain GA ranks (fitness = speed)
    plain = Run(4, algorithm="ga").finish()
    assert Run(4, algorithm="ga", options={"weights": [1.0, 0.0]}).finish() == plain
    weighted = Run(4, algorithm="ga", options={"weights": [1.0, 5.0]})
    curve = weighted.finish()
    assert curve != plain  # cheap robots now survive in place of fast ones
    assert [row["best_so_far"] for row in curve] == sorted(r["best_so_far"] for r in curve)
    sums = weighted.state.data["weighted"]
    last = toy_measures(weighted.state.previous)
    assert sums == pytest.approx([r["speed"] - 5.0 * r["cost_of_transport"] for r in last])
    part = Run(4, algorithm="ga", options={"weights": [1.0, 5.0]})
    for _ in range(3):
        part.step()
    part.state = StrategyState.from_json(json.loads(part.state.to_text()))
    assert part.finish() == curve


def test_a_weighted_ga_keeps_the_best_sum_not_the_fastest() -> None:
    nan = math.nan
    config = StrategySettings.model_validate(
        {
            "population": 4,
            "generations": 5,
            "objectives": OBJECTIVES,
            "selection": "tournament",
            "options": {"weights": [1.0, 1.0]},
        }
    )
    strategy = make_strategy(config, make_encoding("voxel", (2, 2, 2)))
    rng = np.random.default_rng(0)
    previous = [Individual(strategy.encoding.random(rng), "random") for _ in range(4)]
    state = StrategyState(
        seed=0,
        generation=2,
        previous=previous,
        previous_fitness=[0.9, 0.1, nan, 0.5],
        data={"weighted": [-2.0, 0.3, None, -0.1]},
    )
    survivors = [item.parents for item in strategy.ask(state) if item.operator == "survivor"]
    assert survivors == [(1,)]  # the elite by sum, not the fastest (0) nor the failed (2)
    state.data = {}
    with pytest.raises(ValueError, match="state data: weighted must hold one sum"):
        strategy.ask(state)


@pytest.mark.parametrize(
    ("options", "objectives", "words"),
    [
        ({"weights": [1.0]}, OBJECTIVES, "one weight per objective, got 1 for 2"),
        ({"weights": [1.0]}, [], "got 1 for 0 objectives (set `objectives`)"),
        ({"weights": [-1.0, 2.0]}, OBJECTIVES, "each weight >= 0 and one > 0"),
        ({"weights": [0, 0]}, OBJECTIVES, "each weight >= 0 and one > 0"),
    ],
)
def test_bad_weights_are_named(options: dict, objectives: list, words: str) -> None:
    with pytest.raises(ValueError, match=re.escape(words)):
        StrategySettings.model_validate({"objectives": objectives, "options": options})
