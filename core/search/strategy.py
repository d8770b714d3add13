"""The strategy protocol: what every search algorithm is, built in or installed by a user.

A strategy is pure ask/tell over explicit state (`StrategyState`, which round-trips through
JSON), in the spirit of evosax, pyribs and Nevergrad, and its unit is a birth: `cohort(state)`
gives the working copy of one curve row (`softevo.core.search.cohort`), whose births the step
evaluates and tells back in birth order. A generational strategy (`Generational`) asks for
its P births at once and is told them as one generation (`ask`, `breed`, and the shared `tell`,
which gives the next state and the curve row); an asynchronous one (`steady_state`) asks as
births are told. Nothing changes the state it is given, so whoever holds the state
(`softevo run`, the library, the service's coordinator) decides when it becomes the current one.

Algorithms are found by name in the entry-point group `softevo.strategies`
(`softevo.core.search.registry`); each declares its own settings as a pydantic model (`Options`),
which `POST /runs` and `softevo run` validate under `"options"`, and checks its own state on
resume (`check_state`). The shared `SearchSettings` it reads are listed in `uses`, so
`GET /algorithms` shows what each one honours.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Container, Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict

from softevo.core.robots.encodings import Encoding
from softevo.core.search import pareto
from softevo.core.search.archive import Archive
from softevo.core.search.cohort import Cohort, Generation
from softevo.core.search.descriptors import describe
from softevo.core.search.state import Individual, StrategyState, generation_rng
from softevo.core.search.stats import GenerationStats, generation_stats
from softevo.core.search.vectors import ideal_point, objective_values, reference_point

if TYPE_CHECKING:
    from softevo.core.search.settings import SearchSettings

#: Each individual's record of measures (name -> value; NaN or missing: not measured).
Records = Sequence[Mapping[str, float]]


class NoOptions(BaseModel):
    """A strategy with no settings of its own."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)


class Strategy(ABC):
    """One search algorithm. Subclasses set `name`, `summary`, `uses` and `Options`, and give
    the step a `cohort` for each row (`Generational` does, from `breed`); the shared `tell`
    keeps the best so far, the archive and the curve row, and a strategy that needs more
    overrides it (and may keep JSON in `StrategyState.data`; the key `front` there is the
    shared `tell`'s, for a run with `objectives`)."""

    name: ClassVar[str]
    summary: ClassVar[str]
    #: The shared `SearchSettings` this strategy reads (shown by `GET /algorithms`).
    uses: ClassVar[tuple[str, ...]] = ("population", "generations")
    #: This strategy's own settings, validated from the run config's `options`.
    Options: ClassVar[type[BaseModel]] = NoOptions
    #: `Options` validated; a strategy declares it as its own type (`options: ItsOptions`)
    options: BaseModel
    #: Whether `tell` hands `kept` each individual's objective values (NSGA-II, AFPO; the GA
    #: with `weights` sets it per instance, from its options).
    reads_objectives: bool = False

    def __init__(self, config: SearchSettings, encoding: Encoding) -> None:
        self.config = config
        self.encoding = encoding
        self.options = self.Options.model_validate(dict(config.options))

    @classmethod  # noqa: B027 - optional: by default nothing to check
    def check(cls, config: SearchSettings) -> None:
        """Raise ValueError (naming the field) for settings this strategy cannot run with."""

    @classmethod
    def breeds_on(cls, config: SearchSettings, setting: str) -> bool:
        """Whether this strategy's choices read the shared `setting` of `config` (by default: it
        is in `uses`). Objectives and descriptors it does not read only fill what any run keeps
        beside its search (the front, the archive), which `softevo run` says in one line."""
        return setting in cls.uses

    @classmethod
    def state_genomes(cls, config: SearchSettings) -> int:
        """Most genomes the run's state holds at once (the service's budget counts them): by
        default a population, the generation the next is bred from."""
        return config.population

    def start(self, seed: int) -> StrategyState:
        return StrategyState(seed=seed)

    def done(self, state: StrategyState) -> bool:
        return state.generation >= self.config.generations

    @abstractmethod
    def cohort(self, state: StrategyState, known: Container[str] = ()) -> Cohort:
        """The working copy of row `state.generation`, its births asked (a birth whose genome
        is in `known`, the genome hashes evaluated before, is saved: not simulated again)."""

    def ask(self, state: StrategyState) -> list[Individual]:
        """The individuals to evaluate next (always the same for one state): the births the
        row starts with."""
        if self.done(state):
            raise RuntimeError(f"the run has finished its {self.config.generations} generations")
        return [birth.individual for birth in self.cohort(state).window]

    @abstractmethod
    def check_state(self, state: StrategyState) -> None:
        """Raise ValueError (naming the field) for a stored state this strategy cannot go on
        from (`softevo run --resume` asks before anything runs, once the genomes are checked
        against the encoding)."""

    def tell(
        self,
        state: StrategyState,
        individuals: list[Individual],
        fitness: np.ndarray | list[float],
        *,
        measures: Records | None = None,
        **counts: int,
    ) -> tuple[StrategyState, GenerationStats]:
        """The state after `individuals` (what `ask(state)` gave) scored `fitness` (NaN =
        failed) and measured `measures`, and the curve row; `counts` (evaluations, saved, ...)
        are stored with the row."""
        values = np.asarray(fitness, dtype=np.float64)
        if values.shape != (len(individuals),):
            raise ValueError(
                f"expected {len(individuals)} fitness values, got shape {values.shape}"
            )
        records: Records = measures if measures is not None else [{} for _ in individuals]
        if len(records) != len(individuals):
            raise ValueError(f"expected {len(individuals)} measures, got {len(records)}")
        best = _best(state.best, individuals, values, state.generation)
        archive = self.archive(state, individuals, values, records)
        stats = generation_stats(
            state.generation,
            values,
            self.encoding.diversity([individual.genome for individual in individuals]),
            best[1] if best is not None else math.nan,
            **counts,
        )
        if archive is not None:
            stats = replace(stats, coverage=archive.coverage, qd_score=archive.qd_score)
        data = state.data
        objectives = self.config.objectives
        vectors = None  # each individual's objective values, computed once for all who read them
        if objectives or self.reads_objectives:
            vectors = objective_values(objectives, records, values)
        if vectors is not None and objectives:
            front = _front(state.data, vectors)
            data = {**(state.data or {}), FRONT_KEY: front.tolist()}
            nadir = reference_point(objectives)
            volume = pareto.hypervolume(front, nadir)
            scaled = pareto.normalised_hypervolume(front, ideal_point(objectives), nadir)
            stats = replace(
                stats, hypervolume=volume, front_size=len(front), normalised_hypervolume=scaled
            )
        if vectors is not None and self.reads_objectives:
            data = {**(data or {}), **self.kept(state, individuals, vectors)}
        following = StrategyState(
            seed=state.seed,
            generation=state.generation + 1,
            previous=list(individuals),
            previous_fitness=values.tolist(),
            best=best,
            history=[*state.history, stats],
            archive=archive,
            data=data,
        )
        return following, stats

    def kept(
        self, state: StrategyState, individuals: list[Individual], values: np.ndarray
    ) -> dict[str, Any]:
        """What a strategy with `reads_objectives` keeps in `StrategyState.data` (JSON) of a told
        batch whose maximised objective values are `values` ([N, M]); nothing by default."""
        return {}

    def archive(
        self,
        state: StrategyState,
        individuals: list[Individual],
        fitness: np.ndarray,
        records: Records,
    ) -> Archive | None:
        """The archive after these individuals (None for a run without descriptors): each
        robot that did not fail is offered to the cell its descriptors (of its body, and of
        its measures) fall in."""
        config = self.config
        if not config.descriptors:
            return None
        archive = (state.archive or Archive(config.descriptors, config.bins)).copy()
        measured = zip(individuals, fitness, records, strict=True)
        for index, (individual, value, record) in enumerate(measured):
            self.offer(archive, individual, float(value), record, state.generation, index)
        return archive

    def offer(
        self,
        archive: Archive,
        individual: Individual,
        value: float,
        record: Mapping[str, float],
        generation: int,
        index: int,
    ) -> None:
        """Offer one robot that did not fail to the cell its descriptors fall in."""
        if math.isfinite(value):
            labels = self.encoding.labels(individual.genome)
            values = describe(self.config.descriptors, labels, self.encoding.shape, record)
            archive.add(values, value, generation, index, individual.genome)

    @classmethod
    def describe(cls) -> dict[str, Any]:
        """What `GET /algorithms` and `softevo algorithms` show of this strategy."""
        return {
            "name": cls.name,
            "summary": cls.summary,
            "uses": list(cls.uses),
            "options": cls.Options.model_json_schema(),
        }


class Generational(Strategy):
    """A strategy that breeds whole generations: it implements `breed` (and may override
    `first`); each row is the P individuals `ask` gives, told at once."""

    def cohort(self, state: StrategyState, known: Container[str] = ()) -> Cohort:
        return Generation(self, state, known)

    def check_state(self, state: StrategyState) -> None:
        """Parents index the previous generation."""
        size = self.config.population
        for i, item in enumerate(state.previous or []):
            if any(parent >= size for parent in item.parents):
                raise ValueError(
                    f"previous[{i}].parents: {list(item.parents)} indexes past a generation "
                    f"of {size}"
                )

    def ask(self, state: StrategyState) -> list[Individual]:
        """The generation to evaluate next (always the same for one state)."""
        if self.done(state):
            raise RuntimeError(f"the run has finished its {self.config.generations} generations")
        rng = generation_rng(state.seed, state.generation)
        if state.generation == 0 or state.previous is None or state.previous_fitness is None:
            return self.first(rng)
        return self.breed(state, rng)

    def first(self, rng: np.random.Generator) -> list[Individual]:
        """The first individuals: `population` random genomes."""
        population = self.config.population
        return [Individual(self.encoding.random(rng), "random") for _ in range(population)]

    @abstractmethod
    def breed(self, state: StrategyState, rng: np.random.Generator) -> list[Individual]:
        """The next individuals, from the last told ones (`state.previous`, their fitness
        `state.previous_fitness`) or the archive, drawing only from `rng`."""


#: The key of `StrategyState.data` under which a run with objectives keeps its front so far: the
#: distinct maximised points no evaluated individual dominates (strategies keep other keys).
FRONT_KEY = "front"


def _front(data: dict[str, Any] | None, values: np.ndarray) -> np.ndarray:
    """The distinct non-dominated points of the front so far (in `data`) and `values` (failed
    rows left out), sorted (np.unique's order): the same whatever order they were told in."""
    known = np.asarray((data or {}).get(FRONT_KEY, []), dtype=np.float64)
    finite = values[~np.isnan(values).any(axis=1)]
    points = np.unique(np.concatenate([known.reshape(-1, values.shape[1]), finite]), axis=0)
    return points[pareto.nondominated_mask(points)]


def _best(
    best: tuple[Any, float, int] | None,
    individuals: list[Individual],
    values: np.ndarray,
    generation: int,
) -> tuple[Any, float, int] | None:
    """The best (genome, fitness, generation) so far, after `individuals` scored `values`;
    the earlier one keeps a tie."""
    finite = np.isfinite(values)
    if finite.any():
        index = int(np.nanargmax(np.where(finite, values, -np.inf)))
        if best is None or values[index] > best[1]:
            return (individuals[index].genome, float(values[index]), generation)
    return best
