"""A whole evolution run in one process (the library): the generation step of
`softevo.core.search.generation`, generation after generation, with the state held in memory.

The service's driver runs the same step with persistence around it, for the service and for
`softevo run` (its store in the output folder); a run held here is also how the folder's files
and `Result` see a stored run. Genomes already evaluated in this run (survivors, duplicates) are
not simulated again: the run has one simulation setting, so a genome's hash identifies its
fitness.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from softevo.core.config import RunConfig
from softevo.core.evaluator import Evaluator
from softevo.core.robots.robot import Robot
from softevo.core.search.configured import Individual, Strategy, StrategyState, make_strategy
from softevo.core.search.generation import Stepper
from softevo.core.search.stats import CURVE_COLUMNS, GenerationStats, curve_columns  # noqa: F401


@dataclass
class Progress:
    """What a progress display needs after each generation."""

    stats: GenerationStats
    generations: int
    evaluations: int
    saved: int
    elapsed: float

    @property
    def evaluations_per_second(self) -> float:
        return self.evaluations / self.elapsed if self.elapsed > 0 else math.nan


@dataclass
class Evolution:
    """A run in progress in this process: its stepper, state, fitness cache (and each genome's
    record of measures beside it) and counters."""

    config: RunConfig
    stepper: Stepper
    state: StrategyState
    cache: dict[str, float] = field(default_factory=dict)
    measures: dict[str, dict[str, float]] = field(default_factory=dict)
    evaluations: int = 0
    saved: int = 0
    elapsed: float = 0.0

    @classmethod
    def start(cls, config: RunConfig) -> Evolution:
        algorithm = make_strategy(config.strategy_settings(), config.make_encoding())
        return cls(
            config=config,
            stepper=Stepper(
                algorithm,
                config.sim,
                objective=config.objective,
                max_simulations=config.max_simulations,
            ),
            state=algorithm.start(config.seed),
        )

    @classmethod
    def resume(
        cls,
        config: RunConfig,
        state: StrategyState,
        cache: dict[str, float],
        elapsed: float = 0.0,
        measures: dict[str, dict[str, float]] | None = None,
    ) -> Evolution:
        """A stopped run, going on from its state and fitness cache (and measures, which
        behavioural descriptors read): the generations still to run are those an uninterrupted run
        would have run (breeding depends on the seed and the stored generation only), and with
        the cache so are their counts."""
        if state.seed != config.seed:
            raise ValueError(f"the state is of seed {state.seed}, the config of {config.seed}")
        evolution = cls.start(config)
        evolution.state = state
        evolution.cache = dict(cache)
        evolution.measures = dict(measures or {})
        evolution.evaluations = sum(stats.evaluations for stats in state.history)
        evolution.saved = sum(stats.saved for stats in state.history)
        evolution.elapsed = elapsed
        return evolution

    @property
    def algorithm(self) -> Strategy:
        return self.stepper.algorithm

    @property
    def done(self) -> bool:
        return self.stepper.done(self.state, self.evaluations)

    def individuals(self) -> list[Individual]:
        """The current generation (what the next step evaluates)."""
        return self.algorithm.ask(self.state)

    def robot(self, individual: Individual) -> Robot:
        return self.algorithm.encoding.to_robot(individual.genome, self.config.sim)

    def step(self, evaluator: Evaluator) -> GenerationStats:
        """Evaluate and tell one row (the one step of `softevo.core.search.generation`)."""
        step = self.stepper.step(self.state, self.cache, evaluator, measures=self.measures)
        self.state = step.state
        self.evaluations += step.stats.evaluations
        self.saved += step.stats.saved
        self.elapsed += step.seconds
        return step.stats

    def run(
        self,
        evaluator: Evaluator,
        on_generation: Callable[[Progress], None] | None = None,
    ) -> None:
        """Run the remaining generations, reporting after each."""
        while not self.done:
            stats = self.step(evaluator)
            if on_generation is not None:
                on_generation(
                    Progress(
                        stats,
                        self.config.generations,
                        self.evaluations,
                        self.saved,
                        self.elapsed,
                    )
                )

    def best_robot(self) -> tuple[Robot, float, int] | None:
        """The fastest robot so far, its speed (m/s) and the generation it appeared in."""
        best = self.state.best
        if best is None:
            return None
        genome, fitness, generation = best
        return self.algorithm.encoding.to_robot(genome, self.config.sim), fitness, generation

    def curve(self) -> list[dict[str, Any]]:
        """One row per finished generation, with the columns of `CURVE_COLUMNS` (and
        `QD_COLUMNS` for a run with an archive, `PARETO_COLUMNS` for one with objectives)."""
        columns = curve_columns(bool(self.config.descriptors), bool(self.config.objectives))
        rows = (stats.to_json() for stats in self.state.history)
        # a generation run before a column existed (a resumed run) has none of it
        return [{column: row[column] for column in columns if column in row} for row in rows]
