"""The MAP-Elites archive: a grid over descriptors (`softevo.core.search.descriptors`), one elite
per cell, the fittest robot whose descriptors fall in it.

A cell's elite is replaced only by a strictly fitter robot; on equal fitness the smaller genome
hash wins, so the archive after a set of evaluations is the same whatever order they arrived in.
Failed robots (NaN) never enter. The archive is plain data and round-trips through JSON with the
run's GA state, so a run that is taken over after a crash goes on with exactly its archive.

Written here rather than taken from pyribs: its grid archive is these few rules, and pyribs 0.12
brings scipy, pandas and scikit-learn (59 MB of wheels, measured with `pip download ribs`) into
the service and its image; docs/evolution.md says more.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

from softevo.core.robots.genome import Genome, with_genome
from softevo.core.search.descriptors import CATALOGUE


@dataclass(frozen=True)
class Elite:
    """The fittest robot of one cell, and where it was bred (generation, index in it)."""

    cell: tuple[int, ...]
    values: tuple[float, ...]  # descriptor values
    fitness: float
    generation: int
    index: int
    genome: Genome

    def beats(self, other: Elite) -> bool:
        return _better(self.fitness, self.genome, other)

    def to_json(self) -> dict[str, Any]:
        return {
            "cell": list(self.cell),
            "values": list(self.values),
            "fitness": self.fitness,
            "generation": self.generation,
            "index": self.index,
            "genome": self.genome.to_json(),
        }

    @cached_property
    def text(self) -> str:
        """`to_json` as JSON text, made once: an elite is written with the run's state every
        generation it stays an elite."""
        return with_genome(
            {
                "cell": list(self.cell),
                "values": list(self.values),
                "fitness": self.fitness,
                "generation": self.generation,
                "index": self.index,
            },
            self.genome,
        )

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Elite:
        return cls(
            tuple(data["cell"]),
            tuple(float(v) for v in data["values"]),
            float(data["fitness"]),
            int(data["generation"]),
            int(data["index"]),
            Genome.from_json(data["genome"]),
        )


def _better(fitness: float, genome: Genome, elite: Elite) -> bool:
    """Strictly fitter than `elite`, or as fit with the smaller genome hash."""
    if fitness != elite.fitness:
        return fitness > elite.fitness
    return genome.hash < elite.genome.hash


@dataclass
class Archive:
    """Cells by index tuple; `bins[i]` equal cells over descriptor i's range."""

    names: tuple[str, ...]
    bins: tuple[int, ...]
    elites: dict[tuple[int, ...], Elite] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # each descriptor's low end, range and cells, looked up once: every robot is placed
        self._scale = tuple(
            (CATALOGUE[name].low, CATALOGUE[name].high - CATALOGUE[name].low, bins)
            for name, bins in zip(self.names, self.bins, strict=True)
        )

    def cell(self, values: tuple[float, ...]) -> tuple[int, ...]:
        """The cell of descriptor `values` (a value on the range's top edge is in the last)."""
        if len(values) != len(self._scale):
            raise ValueError(f"{len(values)} descriptor values for {len(self._scale)} descriptors")
        return tuple(
            min(max(math.floor((value - low) / span * bins), 0), bins - 1)
            for (low, span, bins), value in zip(self._scale, values, strict=False)
        )

    def add(
        self, values: tuple[float, ...], fitness: float, generation: int, index: int, genome: Genome
    ) -> bool:
        """Offer a robot; True if it became its cell's elite."""
        if not values or not math.isfinite(fitness):
            return False
        cell = self.cell(values)
        current = self.elites.get(cell)
        if current is not None and not _better(fitness, genome, current):
            return False  # (no `Elite` made for a robot that did not get in)
        self.elites[cell] = Elite(cell, values, fitness, generation, index, genome)
        return True

    def ordered(self) -> list[Elite]:
        """Every elite by cell: the order parents are drawn from, the same in every process."""
        return [self.elites[cell] for cell in sorted(self.elites)]

    @property
    def coverage(self) -> float:
        """Filled fraction of the cells."""
        return len(self.elites) / math.prod(self.bins)

    @property
    def qd_score(self) -> float:
        """Sum of the elites' fitness (a cell's elite only ever improves)."""
        return math.fsum(elite.fitness for elite in self.elites.values())

    def copy(self) -> Archive:
        return Archive(self.names, self.bins, dict(self.elites))

    def to_json(self) -> dict[str, Any]:
        return {
            "descriptors": list(self.names),
            "bins": list(self.bins),
            "elites": [elite.to_json() for elite in self.ordered()],
        }

    def to_text(self) -> str:
        """`to_json` as JSON text, each elite's genome as its canonical text."""
        head = json.dumps({"descriptors": list(self.names), "bins": list(self.bins)})[:-1]
        elites = ", ".join(elite.text for elite in self.ordered())
        return f'{head}, "elites": [{elites}]}}'

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Archive:
        elites = (Elite.from_json(item) for item in data["elites"])
        return cls(tuple(data["descriptors"]), tuple(data["bins"]), {e.cell: e for e in elites})
