"""A toy asynchronous strategy of a user's own (issue 50): a (1 + 1) climber with W births in
flight, told birth by birth. It is this one file: its `Cohort`, its state in `data`, its own
resume check, registered through the entry-point group. Nothing in softevo knows of it, yet the
library and the service run it, to the same curve whatever order results land in, and a stop
through its JSON state goes on to the uninterrupted run.
"""

from __future__ import annotations

import math
import sys
from collections import deque
from collections.abc import Container, Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from fastapi.testclient import TestClient
from pydantic import BaseModel, ConfigDict, Field

from softevo.api.app import create_app
from softevo.api.settings import Settings
from softevo.core.config import resolve
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.state import generation_rng
from softevo.strategies import (
    GROUP,
    Birth,
    Cohort,
    Individual,
    Strategy,
    StrategyError,
    StrategyState,
    Told,
    mutant,
    strategies,
    tell_row,
)
from tests.api.finished import finished
from tests.core.search.test_steady_state import Shuffled

NAME = "async-climber"
RUN = {
    "preset": "quick",
    "algorithm": NAME,
    "options": {"window": 3},
    "population": 6,
    "generations": 4,
    "seed": 5,
    "sim": {"duration": 1.0},
}


class ClimberOptions(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)

    window: int = Field(2, ge=1, le=50, description="births in flight at once")


class AsyncClimber(Strategy):
    """Birth n + W is a mutant of the best told so far, bred when birth n is told."""

    name = NAME
    summary = "a (1 + 1) climber with `window` births in flight, told in birth order"
    uses = ("population", "generations", "mutation_genes", "mutation_sigma")
    Options = ClimberOptions
    options: ClimberOptions

    def cohort(self, state: StrategyState, known: Container[str] = ()) -> Climb:
        kept = (state.data or {}).get("climb")
        if kept is None:  # a new run: W random births
            climb = Climb(self, state, None, -math.inf, 0)
            for number in range(self.options.window):
                climb.add(Individual(self.encoding.random(_rng(state, number)), "random"), known)
            return climb
        best = Individual.from_json(kept["best"]) if kept["best"] else None
        climb = Climb(self, state, best, kept["fitness"], kept["told"])
        population = self.config.population
        climb.window.extend(Birth.from_json(item, population) for item in kept["window"])
        return climb

    def check_state(self, state: StrategyState) -> None:
        kept = (state.data or {}).get("climb")
        if state.generation and len((kept or {}).get("window", [])) != self.options.window:
            raise ValueError(f"data.climb.window: expected {self.options.window} births")


def _rng(state: StrategyState, number: int) -> np.random.Generator:
    return generation_rng(state.seed, 1_000_000 + number)  # the seed and the birth alone


@dataclass
class Climb(Cohort):
    strategy: AsyncClimber
    state: StrategyState
    best: Individual | None
    fitness: float
    told: int
    window: deque[Birth] = field(default_factory=deque)
    row: list[Told] = field(default_factory=list)

    @property
    def row_done(self) -> bool:
        return len(self.row) == self.strategy.config.population

    def add(self, individual: Individual, known: Container[str]) -> Birth:
        number = self.told + len(self.window)
        genome_hash = individual.genome.hash
        repeat = genome_hash in known or any(
            b.individual.genome.hash == genome_hash for b in self.window
        )
        row, index = divmod(number, self.strategy.config.population)
        birth = Birth(number, individual, repeat, row, index)
        self.window.append(birth)
        return birth

    def tell(self, fitness: float, record: dict[str, float], known: Container[str]) -> Birth:
        birth = self.window.popleft()
        self.row.append((birth.individual, fitness, record, birth.saved))
        if math.isfinite(fitness) and fitness > self.fitness:
            self.best, self.fitness = birth.individual, fitness
        self.told += 1
        number = self.told + len(self.window)
        rng = _rng(self.state, number)
        config, encoding = self.strategy.config, self.strategy.encoding
        if self.best is None:
            return self.add(Individual(encoding.random(rng), "random"), known)
        return self.add(mutant(config, encoding, self.best, 0, rng), known)

    def finish(self) -> tuple[StrategyState, Any]:
        told, stats = tell_row(self.strategy, self.state, self.row)
        climb = {
            "told": self.told,
            "best": None if self.best is None else self.best.to_json(),
            "fitness": self.fitness if self.best is not None else None,
            "window": [birth.to_json() for birth in self.window],
        }
        return replace(told, data={**(told.data or {}), "climb": climb}), stats


class BreedOnly(Strategy):
    """A generational strategy written against `Strategy` alone: refused, saying what to do."""

    name = "breed-only"
    summary = "breeds, but is no Generational"


def _site(root: Path, name: str, target: str) -> Path:
    """A dist-info folder registering `target` as `name`, as an installed package has it."""
    dist = root / f"{name.replace('-', '_')}-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(f"[{GROUP}]\n{name} = {target}\n")
    return root


@pytest.fixture(scope="module")
def registered(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    """This module's strategy in the entry-point group, as an installed package puts it."""
    root = _site(tmp_path_factory.mktemp("site"), NAME, f"{__name__}:AsyncClimber")
    sys.path.insert(0, str(root))
    strategies.cache_clear()
    yield
    sys.path.remove(str(root))
    strategies.cache_clear()


def test_a_strategy_that_implements_too_little_is_refused_in_one_line(tmp_path: Path) -> None:
    root = _site(tmp_path, "breed-only", f"{__name__}:BreedOnly")
    sys.path.insert(0, str(root))
    strategies.cache_clear()
    try:
        with pytest.raises(StrategyError, match="does not implement check_state, cohort"):
            strategies()
    finally:
        sys.path.remove(str(root))
        strategies.cache_clear()


def _run(evaluator: Any, **changes: Any) -> Evolution:
    evolution = Evolution.start(resolve({**RUN, **changes}))
    evolution.run(evaluator)
    return evolution


def test_the_curve_is_the_same_whatever_order_results_land_in(registered: None) -> None:
    serial = _run(SerialEvaluator())
    assert serial.curve() == _run(Shuffled(4, 3)).curve()
    assert len(serial.curve()) == 4 and serial.curve()[-1]["best_so_far"] > 0
    assert serial.curve() != _run(SerialEvaluator(), options={"window": 1}).curve()


def test_a_stop_through_its_json_state_goes_on_to_the_uninterrupted_run(registered: None) -> None:
    whole = _run(SerialEvaluator())
    half = _run(SerialEvaluator(), generations=2)
    resumed = Evolution.start(resolve(RUN))
    resumed.state = StrategyState.from_json(half.state.to_json())
    resumed.cache, resumed.measures = dict(half.cache), dict(half.measures)
    resumed.run(SerialEvaluator())
    assert resumed.state.to_json(history=False) == whole.state.to_json(history=False)
    broken = replace(half.state, data={"climb": {"window": []}})
    with pytest.raises(ValueError, match=r"data\.climb\.window"):
        resumed.algorithm.check_state(broken)


def test_the_service_runs_it_to_the_library_curve(registered: None, tmp_path: Path) -> None:
    settings = Settings(database_url=f"sqlite:///{tmp_path / 'softevo.db'}", poll_seconds=0.05)
    with TestClient(create_app(settings)) as client:
        response = client.post("/runs", json=RUN)
        assert response.status_code == 201, response.text
        run = finished(client, response.json()["id"])
        assert run["status"] == "completed", run
        served = client.get(f"/runs/{run['id']}/curve").json()["generations"]
    library = _run(SerialEvaluator()).curve()
    keys = ("best", "mean", "best_so_far", "evaluations", "saved")
    assert [[row[k] for k in keys] for row in served] == [[row[k] for k in keys] for row in library]
