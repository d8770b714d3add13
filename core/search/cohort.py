"""Births, the unit of ask and tell: every strategy hands the step a `Cohort`, the working copy
of one curve row, whose `window` holds the births asked and not yet told, oldest first.

The step (`softevo.core.search.stream`) sends births from the window as worker slots free and
tells them back in birth order, one at a time; a told birth may free another (steady-state
breeds birth n + W when birth n is told), or none (a generation asks all of its P births at
once, and its row ends when the last is told). After `population` births, or a generation,
`finish` gives the next state and the curve row. So the step has no branch by strategy, and
no strategy's state is read from outside it.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections import deque
from collections.abc import Container, Mapping, Sequence
from dataclasses import InitVar, dataclass, field
from typing import Any, Protocol

import numpy as np

from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.stats import GenerationStats

#: One told birth: the individual, its fitness (NaN = failed), its record of measures, and
#: whether an earlier birth had its genome (so it was not simulated again).
Told = tuple[Individual, float, dict[str, float], bool]


class Generational(Protocol):
    """What a generation reads of its strategy (`strategy.Generational`)."""

    def ask(self, state: StrategyState) -> list[Individual]: ...
    def tell(
        self,
        state: StrategyState,
        individuals: list[Individual],
        fitness: np.ndarray | list[float],
        *,
        measures: Sequence[Mapping[str, float]] | None = None,
        **counts: int,
    ) -> tuple[StrategyState, GenerationStats]: ...


@dataclass(frozen=True)
class Birth:
    """An individual asked for evaluation: its number in the run, the curve row (generation)
    and place in it it belongs to, and whether an earlier birth had its genome (`saved`: it is
    not simulated again, its fitness is the earlier one's)."""

    number: int
    individual: Individual
    saved: bool
    row: int
    index: int

    def to_json(self) -> dict[str, Any]:
        return {"n": self.number, "saved": self.saved, **self.individual.to_json()}

    @classmethod
    def from_json(cls, data: dict[str, Any], population: int) -> Birth:
        number = int(data["n"])
        row, index = divmod(number, population)
        return cls(number, Individual.from_json(data), bool(data["saved"]), row, index)


class Cohort(ABC):
    """One curve row of a run being told, birth by birth (mutable; `finish` gives the state)."""

    state: StrategyState  # the state the row started from
    window: deque[Birth]  # asked and not told, oldest first
    row: list[Told]  # told, in birth order

    @property
    @abstractmethod
    def row_done(self) -> bool:
        """Whether the row has all its births told (then `finish`)."""

    @property
    def growing(self) -> bool:
        """Whether telling births may breed more before the row ends (then a batch that is not
        full waits for them, up to a worker's second batch)."""
        return True

    @abstractmethod
    def tell(self, fitness: float, record: dict[str, float], known: Container[str]) -> Birth | None:
        """The oldest birth in the window scored `fitness` and measured `record`; the birth
        this frees, if any (saved if `known`, the genome hashes told before, has its genome)."""

    @abstractmethod
    def finish(self) -> tuple[StrategyState, GenerationStats]:
        """The state after the row's births, and its curve row."""

    def go_on(self, state: StrategyState) -> Cohort | None:
        """This cohort, if it is `state`'s and nothing is told yet (the step's end made it), or
        the next row's from it, if it can go on from `state` in memory (None: ask the
        strategy)."""
        return self if self.state is state and not self.row else None


@dataclass
class Generation(Cohort):
    """A generational strategy's row: the P individuals `ask` gives, asked at once (a genome
    that an earlier generation or an earlier member had is saved) and told with the strategy's
    `tell` once all P are in."""

    strategy: Generational
    state: StrategyState
    known: InitVar[Container[str]]
    window: deque[Birth] = field(init=False)
    row: list[Told] = field(default_factory=list)

    def __post_init__(self, known: Container[str]) -> None:
        individuals = self.strategy.ask(self.state)
        start, seen = self.state.generation * len(individuals), set()
        self.window = deque()
        for index, individual in enumerate(individuals):
            genome_hash = individual.genome.hash
            saved = genome_hash in known or genome_hash in seen
            seen.add(genome_hash)
            birth = Birth(start + index, individual, saved, self.state.generation, index)
            self.window.append(birth)
        self.size = len(individuals)

    @property
    def row_done(self) -> bool:
        return len(self.row) == self.size

    @property
    def growing(self) -> bool:
        return False  # every birth of the row was asked at once

    def tell(self, fitness: float, record: dict[str, float], known: Container[str]) -> None:
        birth = self.window.popleft()
        self.row.append((birth.individual, fitness, record, birth.saved))

    def finish(self) -> tuple[StrategyState, GenerationStats]:
        return tell_row(self.strategy, self.state, self.row)


def tell_row(
    strategy: Generational, state: StrategyState, row: list[Told]
) -> tuple[StrategyState, GenerationStats]:
    """The strategy's `tell` of a row's told births, counted as the curve counts them: a
    birth whose genome an earlier one had is `saved`, every other one an evaluation."""
    saved = sum(1 for item in row if item[3])
    return strategy.tell(
        state,
        [item[0] for item in row],
        [item[1] for item in row],
        measures=[item[2] for item in row],
        evaluations=len(row) - saved,
        saved=saved,
    )
