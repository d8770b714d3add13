"""The files `softevo run` leaves in its output folder besides `run.db` (the run in the
service's store, `softevo.run_store`), written from the store after a generation once a second
has passed since the last write (`SAVE_SECONDS`, the service's bound too) and when the run ends
or is interrupted, so an interrupted run still has its partial results:

    run.db            the run as the service stores one (SQLite): what `--resume` goes on from
    config.json       the resolved run configuration (preset merged with overrides)
    curve.csv         one row per generation (the learning curve; a run with objectives adds
                      hypervolume, front_size and normalised_hypervolume, 0-1)
    curve.json        {"run": config, "generations": [rows]}, the same as `softevo run --json`
    best_robot.json   the fastest robot so far, a softevo.robot/1 file
    state.json        the genetic algorithm's state (JSON), for inspection
    cache.json        the fitness of every genome simulated so far (by genome hash), their
                      records of measures (`measures`: name -> value) and the wall time
    population.csv    every individual: generation, index, fitness (empty: failed), operator,
                      then its measures, one column each (docs/physics.md; empty: not measured)
    curve.png, population.png, diversity.png   the run's figures, written at the end
    archive.json, archive.csv, archive.png     a run with descriptors: its MAP-Elites archive
                      (one row per filled cell) and heat map
    front.csv, front.png    a run with objectives: the non-dominated set of every individual
                      evaluated (population.csv's columns), and every robot as a dot with the
                      front drawn over them
    hypervolume.png   a run with objectives: the hypervolume of the front so far against the
                      simulations run (curve.csv's hypervolume and evaluations), and dashed
                      on a right axis its normalised_hypervolume (0-1)

A folder written before run.db (state.json and cache.json were what `--resume` went on from) is
read here (`read_resumable`) to be imported into a store.
"""

from __future__ import annotations

import csv
import json
import math
import os
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from softevo.core.config import ConfigError, resolve
from softevo.core.evolution import Evolution
from softevo.core.nulls import from_null, from_null_record, to_null
from softevo.core.outputs import figures
from softevo.core.outputs.archive_figures import archive_figure
from softevo.core.outputs.front_figure import front_figure, hypervolume_figure, objectives_text
from softevo.core.search.configured import StrategyState
from softevo.core.search.front import front_rows
from softevo.core.search.stats import curve_columns
from softevo.library import Result


def write_json(path: Path, data: Any, indent: int | None = 1) -> None:
    """Write atomically (temp file + rename) so a crash never leaves half a file."""
    temporary = path.with_suffix(path.suffix + ".tmp")
    text = json.dumps(data, indent=indent, allow_nan=False)
    temporary.write_text(text + "\n", encoding="utf-8")
    os.replace(temporary, path)


def write_results(out: Path, evolution: Evolution) -> None:
    out.mkdir(parents=True, exist_ok=True)
    result = Result.of(evolution)
    write_json(out / "config.json", result.config)
    write_json(out / "curve.json", {"run": result.config, "generations": result.curve})
    write_json(out / "state.json", result.state)
    write_json(  # one line, by the C encoder: every genome's record, rewritten every second
        out / "cache.json",
        {
            "generation": evolution.state.generation,  # of state.json, checked on resuming
            "elapsed": evolution.elapsed,
            "fitness": {key: to_null(value) for key, value in evolution.cache.items()},
            "measures": result.measures,
        },
        indent=None,
    )
    if result.best is not None:
        write_json(out / "best_robot.json", result.best)
    temporary = out / "curve.csv.tmp"
    with temporary.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        config = evolution.config
        columns = curve_columns(bool(config.descriptors), bool(config.objectives))
        writer.writerow(columns)
        for row in result.curve:
            writer.writerow(
                [
                    "" if v is None or (isinstance(v, float) and math.isnan(v)) else v
                    for v in (row.get(c) for c in columns)  # a resumed run's older rows
                ]
            )
    os.replace(temporary, out / "curve.csv")


POPULATION_COLUMNS = ("generation", "index", "fitness", "operator")


def write_population(out: Path, rows: Iterable[Any], append: bool = False) -> None:
    """population.csv from the store's rows (generation, index, fitness, operator, measures;
    `softevo.api.store.folders.population`), or `append` them: `POPULATION_COLUMNS`, then one
    column per measure of the first generation's records (an appended file keeps its own)."""
    path = out / "population.csv"
    rows = list(rows)
    if append and not rows:
        return
    if append:
        names = _population_header(path)[len(POPULATION_COLUMNS) :]
    else:
        first = [row[4] or {} for row in rows if row[0] == rows[0][0]] if rows else []
        names = list(dict.fromkeys(name for record in first for name in record))
    temporary = path if append else out / "population.csv.tmp"
    with temporary.open("a" if append else "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        if not append:
            writer.writerow([*POPULATION_COLUMNS, *names])
        for generation, index, fitness, operator, record in rows:
            record = record or {}
            writer.writerow(
                [
                    generation,
                    index,
                    _cell(fitness),
                    operator,
                    *(_cell(record.get(name)) for name in names),
                ]
            )
    if not append:
        os.replace(temporary, path)


def _cell(value: float | None) -> float | str:
    """A number as population.csv writes it: empty when not finite (failed, not measured)."""
    return value if value is not None and math.isfinite(value) else ""


def _population_header(path: Path) -> list[str]:
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            return next(csv.reader(handle), [])
    except FileNotFoundError:
        return []


def read_results(folder: Path) -> tuple[dict[str, Any], list[dict[str, Any]], list[dict[str, Any]]]:
    """(config, curve rows, individuals) of a `softevo run` output folder; ValueError if it is
    not one. An individual's `measures` are population.csv's measure columns (None: empty)."""
    try:
        curve = json.loads((folder / "curve.json").read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:
        raise ValueError(f"{folder}: no readable curve.json ({error})") from None
    return curve.get("run", {}), curve.get("generations", []), read_population(folder)


def read_population(folder: Path) -> list[dict[str, Any]]:
    """population.csv's individuals (none if there is no file); its `measures` are the measure
    columns (None: empty). KeyError, TypeError or ValueError for a file that is not one."""
    individuals: list[dict[str, Any]] = []
    population = folder / "population.csv"
    if not population.exists():
        return individuals
    with population.open(newline="", encoding="utf-8") as handle:
        for row in csv.DictReader(handle):
            if None in row:
                raise ValueError(f"row {len(individuals) + 1} has more cells than the header")
            individuals.append(
                {
                    "generation": int(row["generation"]),
                    "index": int(row["index"]),
                    "fitness": float(row["fitness"]) if row["fitness"] else None,
                    "operator": row["operator"],
                    "measures": {
                        name: float(value) if value else None
                        for name, value in row.items()
                        if name not in POPULATION_COLUMNS
                    },
                }
            )
    return individuals


def write_front(out: Path, individuals: list[dict[str, Any]], specs: Any) -> list[dict[str, Any]]:
    """front.csv: the rows of `individuals` (`read_results`') on the run's front, with
    population.csv's columns."""
    rows = front_rows(specs, individuals)
    names = list(individuals[0]["measures"]) if individuals else []
    with (out / "front.csv").open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow([*POPULATION_COLUMNS, *names])
        for row in rows:
            measures = row["measures"]
            writer.writerow(
                [
                    row["generation"],
                    row["index"],
                    "" if row["fitness"] is None else row["fitness"],
                    row["operator"],
                    *("" if measures.get(n) is None else measures[n] for n in names),
                ]
            )
    return list(rows)


def write_archive(out: Path, evolution: Evolution) -> dict[str, Any] | None:
    """archive.json (the archive as the GA state holds it) and archive.csv (one row per filled
    cell) of a run with descriptors; None for a run without."""
    archive = evolution.state.archive
    if archive is None:
        return None
    data = archive.to_json()
    write_json(out / "archive.json", data)
    temporary = out / "archive.csv.tmp"
    with temporary.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(["cell", *data["descriptors"], "fitness", "generation", "index", "genome"])
        for elite in archive.ordered():
            writer.writerow(
                [
                    "-".join(map(str, elite.cell)),
                    *elite.values,
                    elite.fitness,
                    elite.generation,
                    elite.index,
                    elite.genome.hash,
                ]
            )
    os.replace(temporary, out / "archive.csv")
    return data


def read_resumable(folder: Path, generations: int | None = None) -> Evolution:
    """The stopped run in `folder` (config.json, state.json, cache.json), ready to go on, to
    `generations` if given; ValueError with a one-line reason if it cannot."""
    try:
        config_json = json.loads((folder / "config.json").read_text(encoding="utf-8"))
        state = StrategyState.from_json(
            json.loads((folder / "state.json").read_text(encoding="utf-8"))
        )
        cache = json.loads((folder / "cache.json").read_text(encoding="utf-8"))
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ValueError(f"{folder}: not a resumable `softevo run` folder ({error})") from None
    if cache.get("generation") != state.generation:
        raise ValueError(
            f"{folder}: cache.json is of generation {cache.get('generation')}, state.json of "
            f"{state.generation} (stopped while writing); cannot resume"
        )
    if generations is not None:
        if generations < state.generation:
            raise ValueError(
                f"--generations {generations}: the run already has {state.generation} generations"
            )
        config_json = {**config_json, "generations": generations}
    try:
        config = resolve(config_json)
    except ConfigError as error:
        raise ValueError(f"{folder}/config.json: {error}") from None
    try:
        fitness = {key: from_null(value) for key, value in cache["fitness"].items()}
        measures, elapsed = _measures(cache), float(cache.get("elapsed", 0.0))
    except (AttributeError, KeyError, TypeError, ValueError) as error:
        raise ValueError(f"{folder}/cache.json: not a run's cache ({error!r})") from None
    _trim_population(folder, state.generation)
    return Evolution.resume(config, state, fitness, elapsed, measures)


def _measures(cache: dict[str, Any]) -> dict[str, dict[str, float]]:
    """cache.json's records by genome hash; a folder written before records kept a run's
    headings alone (`heading`, a run with that descriptor), which become records of it."""
    if "measures" in cache:
        return {key: from_null_record(record) for key, record in cache["measures"].items()}
    return {key: {"heading": from_null(value)} for key, value in cache.get("heading", {}).items()}


def _trim_population(folder: Path, generations: int) -> None:
    """Keep population.csv's rows of the first `generations` generations (a run stopped
    between writing its state and its population may hold one more)."""
    path = folder / "population.csv"
    if not path.exists():
        return
    with path.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    kept = [rows[0], *(row for row in rows[1:] if int(row[0]) < generations)] if rows else []
    with path.open("w", newline="", encoding="utf-8") as handle:
        csv.writer(handle, lineterminator="\n").writerows(kept)


def write_figures(out: Path, evolution: Evolution) -> None:
    """curve.png, population.png, diversity.png of the generations finished so far; for a run
    with objectives front.csv, front.png and hypervolume.png; for a run with descriptors
    archive.json, archive.csv and the archive.png heat map."""
    _, curve, individuals = read_results(out)
    as_stored = evolution.config.to_json()
    figures.run_figures(
        curve, individuals, out, figures.run_title(as_stored), figures.fitness_label(as_stored)
    )
    specs = evolution.config.objectives
    if specs:
        write_front(out, individuals, specs)
        task = f"{evolution.config.algorithm}, {figures.run_title(as_stored, fitness=False)}"
        title = f"Pareto front of {objectives_text(specs)}\n{task}"
        figures.save(front_figure(specs, individuals, title), out / "front.png")
        title = f"Hypervolume of {objectives_text(specs)}\n{task}"
        figures.save(hypervolume_figure(specs, curve, title), out / "hypervolume.png")
    archive = write_archive(out, evolution)
    if archive is not None:
        title = f"MAP-Elites archive: {figures.run_title(as_stored)}"
        figure = archive_figure(archive, title, figures.fitness_label(as_stored))
        figures.save(figure, out / "archive.png")
