"""The state of a run of the genetic algorithm, as plain data that round-trips through JSON:
its individuals, where each came from, and each generation's own random generator."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cache
from typing import Any

import numpy as np

from softevo.core.nulls import from_nulls, to_nulls
from softevo.core.robots.genome import Genome, with_genome
from softevo.core.search.archive import Archive
from softevo.core.search.stats import GenerationStats


@dataclass(frozen=True)
class Individual:
    """One member of a generation and where it came from (parents index the previous one)."""

    genome: Genome
    operator: str  # random | survivor | crossover | copy | immigrant (+ "+mutation")
    parents: tuple[int, ...] = ()

    def to_json(self) -> dict[str, Any]:
        return {
            "genome": self.genome.to_json(),
            "operator": self.operator,
            "parents": list(self.parents),
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Individual:
        return cls(Genome.from_json(data["genome"]), data["operator"], tuple(data["parents"]))


def generation_rng(seed: int, generation: int) -> np.random.Generator:
    """The generator of generation `generation` of a run: a function of the seed and g only."""
    return np.random.default_rng(np.random.SeedSequence([seed, generation]))


@dataclass
class StrategyState:
    """Everything needed to go on: the row to run next and the last generation told (the next
    row's births are a function of these and the seed, so they are not stored)."""

    seed: int
    generation: int = 0
    previous: list[Individual] | None = None
    previous_fitness: list[float] | None = None
    best: tuple[Genome, float, int] | None = None  # genome, fitness, generation
    history: list[GenerationStats] = field(default_factory=list)
    archive: Archive | None = None  # quality-diversity runs: the archive after `previous`
    #: A strategy's own state (plain JSON); None, and absent from the JSON, for those without.
    data: dict[str, Any] | None = None

    def to_json(self, history: bool = True) -> dict[str, Any]:
        """JSON; without `history` (kept elsewhere, as the service keeps its curve) the size
        no longer grows with the generations."""

        def individuals(items: list[Individual] | None) -> list[dict] | None:
            return None if items is None else [item.to_json() for item in items]

        archive = {} if self.archive is None else {"archive": self.archive.to_json()}
        data = {} if self.data is None else {"data": self.data}
        return {
            **archive,
            **data,
            "seed": self.seed,
            "generation": self.generation,
            "previous": individuals(self.previous),
            "previous_fitness": _floats_to_json(self.previous_fitness),
            "best": None
            if self.best is None
            else {
                "genome": self.best[0].to_json(),
                "fitness": self.best[1],
                "generation": self.best[2],
            },
            "history": [stats.to_json() for stats in self.history] if history else [],
        }

    def to_text(self, history: bool = True, archive: bool = True) -> str:
        """`to_json` as JSON text (its keys in another order), written every generation by the
        service: each genome enters as its canonical text, computed once for its hash, instead of
        being encoded again (encoding a population's genes cost more than the rest of a
        generation's commit). Without `archive` (the service keeps it in a column of its own,
        which `GET /runs/{id}/archive` reads without the rest), the archive is left out."""
        plain = {
            "seed": self.seed,
            "generation": self.generation,
            "previous_fitness": _floats_to_json(self.previous_fitness),
            "history": [stats.to_json() for stats in self.history] if history else [],
        }
        parts = [
            json.dumps(plain)[:-1],  # without its closing brace
            f', "previous": {_individuals_text(self.previous)}',
        ]
        if self.best is None:
            parts.append(', "best": null')
        else:
            genome, fitness, generation = self.best
            parts.append(
                f', "best": {with_genome({"fitness": fitness, "generation": generation}, genome)}'
            )
        if self.archive is not None and archive:
            parts.append(f', "archive": {self.archive.to_text()}')
        if self.data is not None:
            parts.append(f', "data": {json.dumps(self.data)}')
        return "".join(parts) + "}"

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> StrategyState:
        def individuals(items: list[dict] | None) -> list[Individual] | None:
            return None if items is None else [Individual.from_json(item) for item in items]

        best = data.get("best")
        return cls(
            seed=int(data["seed"]),
            generation=int(data["generation"]),
            previous=individuals(data.get("previous")),
            previous_fitness=_floats_from_json(data.get("previous_fitness")),
            best=None
            if best is None
            else (
                Genome.from_json(best["genome"]),
                float(best["fitness"]),
                int(best["generation"]),
            ),
            history=[GenerationStats.from_json(item) for item in data.get("history", [])],
            archive=Archive.from_json(data["archive"]) if data.get("archive") else None,
            data=_data(data.get("data")),
        )


def _data(value: Any) -> dict[str, Any] | None:
    """A strategy's own state as stored: an object, or None."""
    if value is not None and not isinstance(value, dict):
        raise ValueError(f"data: a strategy's state is an object, got {type(value).__name__}")
    return value


@cache
def _quoted(text: str) -> str:
    """A string as JSON (operators: a handful of names, so each is encoded once)."""
    return json.dumps(text)


def parents_text(parents: tuple[int, ...]) -> str:
    """Parent indices as the JSON text `json.dumps` gives them, without its encoder."""
    return f"[{', '.join(str(int(index)) for index in parents)}]"


def _individuals_text(items: list[Individual] | None) -> str:
    """JSON text of `[item.to_json() for item in items]` (None: null), genomes as they are."""
    if items is None:
        return "null"
    return "[{}]".format(
        ", ".join(
            f'{{"genome": {item.genome.canonical}, "operator": {_quoted(item.operator)}, '
            f'"parents": {parents_text(item.parents)}}}'
            for item in items
        )
    )


def _floats_to_json(values: list[float] | None) -> list[float | None] | None:
    return None if values is None else to_nulls(values)


def _floats_from_json(values: list[float | None] | None) -> list[float] | None:
    return None if values is None else from_nulls(values).tolist()
