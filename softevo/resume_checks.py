"""What `softevo run --resume DIR` checks in a folder before it goes on: the folder is something
a user hands over, and may have been edited, truncated or mixed with another run's files. Every
file is read whole and checked against the run's config (`config.json`, resolved as a new run's
would be) before anything is written or simulated, so a tampered folder ends in one line naming
the file and the field, never a traceback halfway through a generation, and nothing in it is
silently accepted (a population that is not the config's, a fitness list that does not match
it, genes out of their range, parents that are not indices).
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

from softevo.core.config import ConfigError, RunConfig, resolve
from softevo.core.robots.encodings import Encoding, EncodingError
from softevo.core.robots.genome import Genome
from softevo.core.search.configured import make_strategy
from softevo.core.search.state import StrategyState


class ResumeError(ValueError):
    """A folder that cannot be resumed; the message is one line naming the file and field."""


def check_folder(folder: Path, generations: int | None = None) -> None:
    """Refuse (ResumeError) a folder whose config, state, cache or population cannot be
    resumed as they are, or do not belong together; return None if they can."""
    config_json = _read(folder / "config.json")
    state_json, cache_json = _read(folder / "state.json"), _read(folder / "cache.json")
    if not isinstance(config_json, dict):
        raise ResumeError(f"config.json: expected an object, got {_kind(config_json)}")
    _check_state_json(state_json)
    _check_cache_json(cache_json)
    if generations is not None:
        config_json = {**config_json, "generations": generations}
    try:
        config = resolve(config_json)
    except ConfigError as error:
        raise ResumeError(f"config.json: {error}") from None
    try:
        state = StrategyState.from_json(state_json)
    except (KeyError, TypeError, ValueError, AttributeError) as error:
        raise ResumeError(f"state.json: not a run's state ({error!r})") from None
    _check_state(config, state, state_json)
    _check_population_csv(folder / "population.csv")


def _read(path: Path) -> Any:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ResumeError(f"{path.name}: missing (not a `softevo run` folder)") from None
    except OSError as error:
        raise ResumeError(f"{path.name}: cannot read ({error.strerror})") from None
    except RecursionError:
        raise ResumeError(f"{path.name}: nested too deeply to be a run's file") from None
    except ValueError as error:  # JSONDecodeError, and text that is not UTF-8
        raise ResumeError(f"{path.name}: not JSON ({error})") from None


def _kind(value: Any) -> str:
    return "null" if value is None else type(value).__name__


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any, nullable: bool = False) -> bool:
    if value is None:
        return nullable
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _expect(ok: bool, where: str, what: str, value: Any) -> None:
    if not ok:
        shown = repr(value) if len(repr(value)) <= 40 else _kind(value)
        raise ResumeError(f"{where}: expected {what}, got {shown}")


def _check_state_json(state: Any) -> None:
    """The shape and types of state.json, field by field (what StrategyState.from_json would
    otherwise coerce silently: "ab" as parents, 1.5 as a gene)."""
    _expect(isinstance(state, dict), "state.json", "an object", state)
    for name in ("seed", "generation"):
        _expect(_is_int(state.get(name)), f"state.json: {name}", "an integer", state.get(name))
    _expect(state["generation"] >= 0, "state.json: generation", "0 or more", state["generation"])
    items = state.get("previous")
    _expect(items is None or isinstance(items, list), "state.json: previous", "a list", items)
    for i, item in enumerate(items or []):
        _check_individual_json(item, f"state.json: previous[{i}]")
    fitness = state.get("previous_fitness")
    _expect(
        fitness is None or isinstance(fitness, list),
        "state.json: previous_fitness",
        "a list",
        fitness,
    )
    for i, value in enumerate(fitness or []):
        _expect(
            _is_number(value, nullable=True),
            f"state.json: previous_fitness[{i}]",
            "a number or null",
            value,
        )
    best = state.get("best")
    if best is not None:
        _expect(isinstance(best, dict), "state.json: best", "an object", best)
        _check_genome_json(best.get("genome"), "state.json: best.genome")
        _expect(
            _is_number(best.get("fitness"), nullable=True),
            "state.json: best.fitness",
            "a number or null",
            best.get("fitness"),
        )
        _expect(
            _is_int(best.get("generation")),
            "state.json: best.generation",
            "an integer",
            best.get("generation"),
        )
    history = state.get("history", [])
    _expect(
        isinstance(history, list) and all(isinstance(h, dict) for h in history),
        "state.json: history",
        "a list of objects",
        history,
    )
    archive = state.get("archive")
    if archive:
        _expect(
            isinstance(archive, dict) and isinstance(archive.get("elites"), list),
            "state.json: archive",
            "an object with elites",
            archive,
        )
        for i, elite in enumerate(archive["elites"]):
            _expect(isinstance(elite, dict), f"state.json: archive.elites[{i}]", "an object", elite)
            _check_genome_json(elite.get("genome"), f"state.json: archive.elites[{i}].genome")


def _check_individual_json(item: Any, where: str) -> None:
    _expect(isinstance(item, dict), where, "an object", item)
    _check_genome_json(item.get("genome"), f"{where}.genome")
    _expect(
        isinstance(item.get("operator"), str), f"{where}.operator", "a name", item.get("operator")
    )
    parents = item.get("parents")
    _expect(
        isinstance(parents, list) and all(_is_int(p) and p >= 0 for p in parents),
        f"{where}.parents",
        "a list of indices",
        parents,
    )


def _check_genome_json(genome: Any, where: str) -> None:
    _expect(isinstance(genome, dict), where, "an object", genome)
    _expect(
        isinstance(genome.get("encoding"), str),
        f"{where}.encoding",
        "a name",
        genome.get("encoding"),
    )
    discrete, real = genome.get("discrete"), genome.get("real", [])
    _expect(
        isinstance(discrete, list) and all(_is_int(g) for g in discrete),
        f"{where}.discrete",
        "a list of integers",
        discrete,
    )
    _expect(
        isinstance(real, list) and all(_is_number(g) for g in real),
        f"{where}.real",
        "a list of finite numbers",
        real,
    )


def _check_cache_json(cache: Any) -> None:
    _expect(isinstance(cache, dict), "cache.json", "an object", cache)
    _expect(
        _is_int(cache.get("generation")),
        "cache.json: generation",
        "an integer",
        cache.get("generation"),
    )
    _expect(
        _is_number(cache.get("elapsed", 0.0)) and cache.get("elapsed", 0.0) >= 0,
        "cache.json: elapsed",
        "seconds, 0 or more",
        cache.get("elapsed"),
    )
    fitness = cache.get("fitness")
    _expect(isinstance(fitness, dict), "cache.json: fitness", "an object", fitness)
    for key, value in fitness.items():
        _expect(
            _is_number(value, nullable=True),
            f"cache.json: fitness[{key!r}]",
            "a number or null",
            value,
        )
    for name in ("measures", "heading"):
        records = cache.get(name, {})
        _expect(isinstance(records, dict), f"cache.json: {name}", "an object", records)


def _check_state(config: RunConfig, state: StrategyState, raw: dict[str, Any]) -> None:
    """The state against the run's config: its seed, generation, population sizes, the genes
    of every genome under the config's encoding, parents within the previous generation."""
    if state.seed != config.seed:
        raise ResumeError(f"state.json: seed {state.seed}, but config.json's seed is {config.seed}")
    if state.generation > config.generations:
        raise ResumeError(
            f"state.json: generation {state.generation} is past the config's "
            f"{config.generations} generations"
        )
    if state.generation > 0 and state.previous is None:
        raise ResumeError(f"state.json: previous is null at generation {state.generation}")
    encoding = config.make_encoding()
    size = config.population
    items = state.previous or []
    if state.previous is not None and len(items) != size:
        raise ResumeError(
            f"state.json: previous holds {len(items)} individuals, but "
            f"config.json's population is {size}"
        )
    for i, item in enumerate(items):
        _check_genome(encoding, item.genome, f"state.json: previous[{i}].genome")
    try:  # what the strategy keeps of its own (parents, births in flight)
        make_strategy(config.strategy_settings(), encoding).check_state(state)
    except ValueError as error:
        raise ResumeError(f"state.json: {error}") from None
    fitness = state.previous_fitness
    if state.previous is not None and (fitness is None or len(fitness) != len(state.previous)):
        count = "none" if fitness is None else len(fitness)
        raise ResumeError(
            f"state.json: previous_fitness holds {count} values for "
            f"{len(state.previous)} individuals"
        )
    if state.best is not None:
        _check_genome(encoding, state.best[0], "state.json: best.genome")
    if state.archive is not None:
        _check_archive(config, encoding, state)
    if len(raw.get("history", [])) not in (0, state.generation):
        raise ResumeError(
            f"state.json: history holds {len(raw['history'])} generations, "
            f"the state is at generation {state.generation}"
        )


def _check_genome(encoding: Encoding, genome: Genome, where: str) -> None:
    try:
        encoding.check_stored(genome)
    except EncodingError as error:
        raise ResumeError(f"{where}: {error} (another run's genome?)") from None


def _check_archive(config: RunConfig, encoding: Encoding, state: StrategyState) -> None:
    archive = state.archive
    assert archive is not None
    if archive.names != config.descriptors or archive.bins != config.bins:
        raise ResumeError(
            f"state.json: archive of {list(archive.names)} x {list(archive.bins)}, "
            f"but config.json asks for {list(config.descriptors)} x "
            f"{list(config.bins)}"
        )
    for cell, elite in archive.elites.items():
        where = f"state.json: archive elite {list(cell)}"
        if len(cell) != len(archive.bins) or not all(
            _is_int(c) and 0 <= c < b for c, b in zip(cell, archive.bins, strict=False)
        ):
            raise ResumeError(f"{where}: not a cell of {list(archive.bins)}")
        _check_genome(encoding, elite.genome, f"{where}.genome")


def _check_population_csv(path: Path) -> None:
    """population.csv, which resuming trims to the state's generations: a header, then rows
    that start with their generation."""
    if not path.exists():
        return
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            for number, row in enumerate(csv.reader(handle)):
                if number and not (row and row[0].isdigit()):
                    raise ResumeError(
                        f"population.csv: row {number + 1} does not start with its generation"
                    )
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise ResumeError(f"population.csv: cannot read ({error})") from None
