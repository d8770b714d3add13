"""A whole evolution run in one process: ask, look up the cache, evaluate the rest, tell.

Used by `softevo run`; the service's coordinator drives the same `GeneticAlgorithm` with its own
persistence. Genomes already evaluated in this run (survivors, duplicates) are not simulated
again: the run has one simulation setting, so a genome's hash identifies its fitness.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from softevo.core.config import RunConfig
from softevo.core.evaluator import Evaluator
from softevo.core.ga.algorithm import GeneticAlgorithm, Individual
from softevo.core.ga.stats import CURVE_COLUMNS, GenerationStats
from softevo.core.robot import Robot
from softevo.core.robot_file import robot_to_json


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
    """A run in progress: the algorithm, its fitness cache and its counters."""

    config: RunConfig
    algorithm: GeneticAlgorithm
    cache: dict[str, float] = field(default_factory=dict)
    evaluations: int = 0
    saved: int = 0
    elapsed: float = 0.0

    @classmethod
    def start(cls, config: RunConfig) -> Evolution:
        algorithm = GeneticAlgorithm.start(config.ga_config(), config.make_encoding(), config.seed)
        return cls(config=config, algorithm=algorithm)

    @property
    def done(self) -> bool:
        return self.algorithm.done

    def robot(self, individual: Individual) -> Robot:
        return self.algorithm.encoding.to_robot(individual.genome, self.config.sim)

    def step(self, evaluator: Evaluator) -> GenerationStats:
        """Evaluate and tell one generation."""
        started = time.perf_counter()
        individuals = self.algorithm.ask()
        hashes = [individual.genome.hash for individual in individuals]
        missing: dict[str, int] = {}
        for index, genome_hash in enumerate(hashes):
            if genome_hash not in self.cache and genome_hash not in missing:
                missing[genome_hash] = index
        if missing:
            files = [robot_to_json(self.robot(individuals[i])) for i in missing.values()]
            fitness = evaluator.evaluate(files)
            self.cache.update(zip(missing, fitness.tolist(), strict=True))
        saved = len(individuals) - len(missing)
        self.evaluations += len(missing)
        self.saved += saved
        values = np.array([self.cache[h] for h in hashes], dtype=np.float64)
        stats = self.algorithm.tell(values, evaluations=len(missing), saved=saved)
        self.elapsed += time.perf_counter() - started
        return stats

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
        best = self.algorithm.state.best
        if best is None:
            return None
        genome, fitness, generation = best
        return self.algorithm.encoding.to_robot(genome, self.config.sim), fitness, generation

    def curve(self) -> list[dict[str, Any]]:
        """One row per finished generation, with the columns of `CURVE_COLUMNS`."""
        rows = []
        for stats in self.algorithm.state.history:
            data = stats.to_json()
            rows.append({column: data[column] for column in CURVE_COLUMNS})
        return rows
