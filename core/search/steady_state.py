"""`steady-state`: asynchronous evolution that gives the same result on any number of workers.

Births are numbered 0, 1, 2, ... Births 0 to max(P, W)-1 (P the population) are random genomes;
every later birth n is bred from the population as it stands once births 0 .. n-W have been
told, in birth order, where W (`window`) is how many births may be in flight at once. A result that
lands early waits for the births before it, so the run depends on the seed alone: not on the
number of workers, their speed, the backend or a takeover, and robots that simulate quickly gain
nothing (the evaluation-time bias of asynchronous EAs, Scott & De Jong 2015, cannot arise).

Parents: two tournaments of `tournament_size` among the population (or, with
`parents: "archive"`, two elites drawn uniformly: a steady-state MAP-Elites), crossed and mutated
as the GA does (or, with options `variation: "explore"`, by exploring variation: every gene
mutated with probability `mutated_genes` / n, and a child that repeats a member or a birth in
flight re-drawn); with probability `immigrants` a birth is a random genome instead. Replacement:
a told birth joins a population not yet full; after that it replaces the worst member if it is
strictly better (the oldest of equally bad members goes first), so the best never falls and a
failed robot never enters. Every P told births make one curve row ("generation").

The births in flight live in `StrategyState.data["steady"]`, so a stored state resumes the same
sequence; `Nursery` is the mutable working copy the generation step tells one birth at a time.
"""

from __future__ import annotations

import heapq
import math
from collections import Counter, deque
from collections.abc import Container
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from pydantic import Field

from softevo.core.search import operators
from softevo.core.search.archive import Archive
from softevo.core.search.cohort import Birth, Cohort, Told, tell_row
from softevo.core.search.state import Individual, StrategyState
from softevo.core.search.stats import GenerationStats
from softevo.core.search.strategy import Strategy
from softevo.core.search.variation import VariationOptions, explore_child, mate

if TYPE_CHECKING:
    from softevo.core.search.settings import SearchSettings

#: The key of `StrategyState.data` holding the births in flight and the population's birth numbers.
KEY = "steady"
#: The widest window, in populations: the W births in flight are stored with every row (and its
#: first W births are random), and 4 populations already fed two RQ workers (BENCHMARKS.md).
MAX_WINDOW = 8
#: Mixed into every birth's seed, apart from the generations' (`generation_rng`).
_BIRTHS = 0x5EED


class SteadyStateOptions(VariationOptions):
    """The in-flight window, where parents come from, and how a child is made (the paper's
    operators unless `variation` is explore)."""

    window: int | None = Field(
        None,
        ge=1,
        le=10_000,
        description="W, the births that may be in flight at once: birth n is bred once births "
        "up to n-W are told; births below max(population, W) are random. Null: the population; "
        "at most 8 populations. "
        "A birth that repeats a genome is not simulated but still holds its place, so where "
        "most children repeat a parent (paper-voxel: 3 in 4) a window of 2-4 populations keeps "
        "two cores busy; a smaller one selects on fresher results",
    )
    parents: Literal["population", "archive"] = Field(
        "population",
        description="population: two tournaments of tournament_size; archive: two elites "
        "drawn uniformly from the archive (needs descriptors and bins): a steady-state "
        "MAP-Elites",
    )


def window_size(options: dict[str, Any], population: int) -> int:
    """W of a run whose `options` are these: the births its state holds in flight."""
    return options.get("window") or population


def birth_rng(seed: int, birth: int) -> np.random.Generator:
    """The generator of birth `birth` of a run: a function of the seed and n only."""
    return np.random.default_rng(np.random.SeedSequence([seed, _BIRTHS, birth]))


class SteadyState(Strategy):
    name = "steady-state"
    summary = (
        "asynchronous steady-state evolution: W births in flight, each bred as soon as a slot "
        "frees and told in birth order, so the result does not depend on workers or timing"
    )
    uses = (
        "population",
        "generations",
        "tournament_size",
        "crossover_probability",
        "mutation_probability",
        "mutation_genes",
        "mutation_sigma",
        "immigrants",
    )
    Options = SteadyStateOptions
    options: SteadyStateOptions  # typed as its own, which __init__ validates

    @classmethod
    def check(cls, config: SearchSettings) -> None:
        window = config.options.get("window")
        if isinstance(window, int) and window > MAX_WINDOW * config.population:
            raise ValueError(
                f"options.window: {window} is more than {MAX_WINDOW} populations "
                f"({MAX_WINDOW * config.population}); every birth in flight is kept in the state"
            )
        if config.options.get("parents") == "archive" and not config.descriptors:
            raise ValueError('options.parents: "archive" needs descriptors and bins')

    @classmethod
    def breeds_on(cls, config: SearchSettings, setting: str) -> bool:
        """With `parents: "archive"` the parents are the archive's elites."""
        archive = setting in ("descriptors", "bins") and config.options.get("parents") == "archive"
        return archive or super().breeds_on(config, setting)

    @classmethod
    def state_genomes(cls, config: SearchSettings) -> int:
        """The population and the W births in flight."""
        return config.population + window_size(config.options, config.population)

    @property
    def window(self) -> int:
        return window_size(self.config.options, self.config.population)

    @property
    def total(self) -> int:
        return self.config.population * self.config.generations

    def cohort(self, state: StrategyState, known: Container[str] = ()) -> Nursery:
        """The working copy of `state` the step tells births to; `known` (genome hashes
        evaluated before) marks the first births of a new run that repeat a genome."""
        kept = (state.data or {}).get(KEY)
        if kept is None:  # a new run: births 0 .. W-1, random
            nursery = Nursery(self, state, [], [], [], 0, deque())
            for number in range(self.window):
                nursery.add(number, self._random(state.seed, number), known)
            return nursery
        population = self.config.population
        window = deque(Birth.from_json(item, population) for item in kept["window"])
        return Nursery(
            self,
            state,
            list(state.previous or []),
            list(state.previous_fitness or []),
            list(kept["births"]),
            int(kept["told"]),
            window,
        )

    def check_state(self, state: StrategyState) -> None:
        """The births told are the rows', a birth number per member, the window after them,
        each a genome of the encoding; parents are births told."""
        kept = (state.data or {}).get(KEY)
        if state.generation == 0 and kept is None:
            return
        told = self.config.population * state.generation
        if not isinstance(kept, dict) or kept.get("told") != told:
            got = kept.get("told") if isinstance(kept, dict) else type(kept).__name__
            raise ValueError(f"data.steady.told: expected {told} (the rows' births), got {got!r}")
        births = kept.get("births")
        members = len(state.previous or [])
        if (
            not isinstance(births, list)
            or len(births) != members
            or not all(type(n) is int and 0 <= n < told for n in births)
        ):
            raise ValueError(f"data.steady.births: expected a birth number below {told} a member")
        window = kept.get("window")
        if not isinstance(window, list) or len(window) != self.window:
            got = len(window) if isinstance(window, list) else type(window).__name__
            raise ValueError(
                f"data.steady.window: expected a list of {self.window} births (the window), "
                f"got {got}"
            )
        for i, item in enumerate(window):
            _check_birth(self, item, told + i, f"data.steady.window[{i}]")
        for i, member in enumerate(state.previous or []):
            if any(parent >= told for parent in member.parents):
                raise ValueError(
                    f"previous[{i}].parents: {list(member.parents)} indexes past {told} births told"
                )

    def _random(self, seed: int, number: int) -> Individual:
        return Individual(self.encoding.random(birth_rng(seed, number)), "random")

    def bred(self, nursery: Nursery, number: int) -> Individual:
        """Birth `number` (>= W), from the nursery's population and archive as they stand."""
        config = self.config
        rng = birth_rng(nursery.state.seed, number)
        if number < config.population:
            return Individual(self.encoding.random(rng), "random")
        if rng.random() < config.immigrants:
            return Individual(self.encoding.random(rng), "immigrant")
        if self.options.parents == "archive" and nursery.archive is not None:
            elites = nursery.archive.ordered()
            if elites:
                picks = [elites[int(i)] for i in rng.integers(0, len(elites), size=2)]
                pair = (Individual(picks[0].genome, "elite"), Individual(picks[1].genome, "elite"))
                child = self.child(nursery, pair, rng)
                born = [elite.generation * config.population + elite.index for elite in picks]
                return replace(child, parents=tuple(born[i] for i in child.parents))
        chosen = operators.tournament(nursery.scores(), 2, config.tournament_size, rng).tolist()
        pair = (nursery.population[chosen[0]], nursery.population[chosen[1]])
        child = self.child(nursery, pair, rng)
        parents = tuple(nursery.births[chosen[i]] for i in child.parents)
        return Individual(child.genome, child.operator, parents)

    def child(
        self, nursery: Nursery, pair: tuple[Individual, Individual], rng: np.random.Generator
    ) -> Individual:
        """One child of `pair` (parents named 0 and 1): the paper's operators, or exploring
        ones, re-drawn while it repeats a member or a birth in flight (what the nursery holds
        is the same on any worker count; results that landed early are not asked)."""
        config, encoding = self.config, self.encoding
        if self.options.variation != "explore":
            return mate(config, encoding, pair, (0, 1), rng, children=1)[0]
        seen = {member.genome.hash for member in nursery.population}
        seen.update(nursery.hashes)
        return explore_child(config, encoding, pair, self.options.mutated_genes, seen, rng)


@dataclass
class Nursery(Cohort):
    """One row of a steady-state run being told, birth by birth (mutable; `finish` gives the
    state). `population`, `fitness` and `births` are the members, their fitness and birth
    numbers; `window` the births in flight, oldest first."""

    strategy: SteadyState
    state: StrategyState
    population: list[Individual]
    fitness: list[float]
    births: list[int]
    told: int
    window: deque[Birth]
    row: list[Told] = field(default_factory=list)
    hashes: Counter[str] = field(default_factory=Counter)  # of the window's genomes
    following: StrategyState | None = None  # the state `finish` gave
    #: (rank, birth, slot) of every member, a heap: its top is the member a better birth
    #: replaces (the worst fitness, NaN lowest; of equals, the oldest birth), in O(log P)
    worst: list[tuple[float, int, int]] = field(default_factory=list, repr=False)
    #: `fitness` as an array for the tournaments, kept in step with it (None: to be made)
    _scores: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        self.hashes.update(birth.individual.genome.hash for birth in self.window)
        ranked = zip(self.fitness, self.births, strict=True)
        self.worst = [(_rank(value), number, slot) for slot, (value, number) in enumerate(ranked)]
        heapq.heapify(self.worst)
        self.archive = None  # the archive as it stands, when parents are drawn from it
        if self.strategy.options.parents == "archive":
            config = self.strategy.config
            kept = self.state.archive or Archive(config.descriptors, config.bins)
            self.archive = kept.copy()

    def scores(self) -> np.ndarray:
        """The members' fitness as an array, made once while the population is full (a
        replacement writes its slot), not once a birth."""
        if self._scores is None or len(self._scores) != len(self.fitness):
            self._scores = np.array(self.fitness, dtype=np.float64)
        return self._scores

    @property
    def row_done(self) -> bool:
        return len(self.row) == self.strategy.config.population

    def add(self, number: int, individual: Individual, known: Container[str]) -> Birth:
        """Birth `number` joins the window; it is `saved` if an earlier birth had its genome
        (told: in `known`; in flight: in the window)."""
        genome_hash = individual.genome.hash
        saved = genome_hash in known or genome_hash in self.hashes
        row, index = divmod(number, self.strategy.config.population)
        birth = Birth(number, individual, saved, row, index)
        self.window.append(birth)
        self.hashes[genome_hash] += 1
        return birth

    def tell(self, fitness: float, record: dict[str, float], known: Container[str]) -> Birth:
        """The oldest birth in flight scored `fitness`: it joins the population (or not), and
        the birth W later is bred and returned. It is bred past the run's last birth too (the
        step never sends those), so a run resumed with more generations has the births an
        uninterrupted longer run had."""
        birth = self.window.popleft()
        genome_hash = birth.individual.genome.hash
        self.hashes[genome_hash] -= 1
        if not self.hashes[genome_hash]:
            del self.hashes[genome_hash]
        self.row.append((birth.individual, fitness, record, birth.saved))
        self._replace(birth, fitness)
        if self.archive is not None:  # parents drawn from it: offered now, as `finish` will
            index = len(self.row) - 1
            self.strategy.offer(
                self.archive, birth.individual, fitness, record, self.state.generation, index
            )
        self.told += 1
        number = self.told - 1 + self.strategy.window
        return self.add(number, self.strategy.bred(self, number), known)

    def _replace(self, birth: Birth, fitness: float) -> None:
        if len(self.population) < self.strategy.config.population:
            self.population.append(birth.individual)
            self.fitness.append(fitness)
            self.births.append(birth.number)
            heapq.heappush(self.worst, (_rank(fitness), birth.number, len(self.births) - 1))
            return
        if math.isnan(fitness):
            return
        lowest, _, slot = self.worst[0]  # the worst member (a total order: ties never arise)
        if fitness > lowest:
            self.population[slot] = birth.individual
            self.fitness[slot] = fitness
            if self._scores is not None and len(self._scores) == len(self.fitness):
                self._scores[slot] = fitness
            self.births[slot] = birth.number
            heapq.heapreplace(self.worst, (fitness, birth.number, slot))

    def finish(self) -> tuple[StrategyState, GenerationStats]:
        """The state after the row's P births, and its curve row."""
        told, stats = tell_row(self.strategy, self.state, self.row)
        data = {
            **(told.data or {}),
            KEY: {
                "told": self.told,
                "births": list(self.births),
                "window": [birth.to_json() for birth in self.window],
            },
        }
        state = replace(
            told, previous=list(self.population), previous_fitness=list(self.fitness), data=data
        )
        self.following = state  # the next row goes on from this working copy, not from JSON
        return state, stats

    def go_on(self, state: StrategyState) -> Cohort | None:
        """The next row from this working copy, if `state` is what `finish` gave."""
        if self.following is not state:
            return super().go_on(state)
        self.state, self.row, self.following = state, [], None
        return self


def _check_birth(strategy: SteadyState, item: Any, number: int, where: str) -> None:
    """Refuse (ValueError naming `where`) a stored birth that is not birth `number` of a genome
    of the strategy's encoding."""
    try:
        birth = Birth.from_json(item, strategy.config.population)
        strategy.encoding.check_stored(birth.individual.genome)
    except (KeyError, TypeError, ValueError, AttributeError) as error:
        raise ValueError(f"{where}: not a birth of this run ({error})") from None
    parents = birth.individual.parents
    if birth.number != number or not isinstance(item.get("saved"), bool):
        raise ValueError(
            f"{where}: expected birth {number} with saved true or false, got birth {birth.number}"
        )
    if not isinstance(birth.individual.operator, str) or not all(
        type(p) is int and p >= 0 for p in parents
    ):
        raise ValueError(f"{where}: expected an operator's name and parents' birth numbers")


def _rank(fitness: float) -> float:
    """A member's fitness for replacement: a failed robot (NaN) ranks below every other."""
    return -math.inf if math.isnan(fitness) else fitness
