"""A run with several objectives end to end (issue 36): the library and `softevo run`, with the
actuators' work measured because the objectives read it."""

from __future__ import annotations

import csv
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from softevo import library
from softevo.core.config import resolve
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search import pareto
from softevo.core.search.front import front_values
from softevo.core.search.vectors import objective_values, reference_point
from softevo.results import read_results, write_results
from tests.softevo.inprocess import softevo

SMALL = {
    "preset": "quick",
    "shape": [2, 2, 2],
    "population": 6,
    "generations": 3,
    "sim": {"duration": 1.0},
    "seed": 3,
}
OBJECTIVES = ["speed", "-cost_of_transport"]


def test_library_nsga2_run_measures_energy_and_curves_its_front() -> None:
    result = library.evolve(SMALL, algorithm="nsga2", objectives=OBJECTIVES, workers=1)
    records = list(result.measures.values())
    assert records and all(math.isfinite(r["cost_of_transport"]) for r in records)
    config = library.configure(SMALL, objectives=OBJECTIVES)
    speeds = np.array([r["speed"] for r in records])
    values = objective_values(config.objectives, records, speeds)
    last = result.curve[-1]
    assert last["front_size"] == len(np.unique(values[pareto.nondominated_mask(values)], axis=0))
    assert last["hypervolume"] == pareto.hypervolume(values, reference_point(config.objectives))
    assert last["hypervolume"] > 0
    front = front_values(config.objectives, result.front)
    assert len(front) == last["front_size"]  # distinct genomes here, distinct points there
    assert all(not pareto.dominates(a, b) for a in front for b in front)
    again = library.evolve(SMALL, algorithm="nsga2", objectives=OBJECTIVES, workers=2)
    assert again.curve == result.curve and again.front == result.front  # any number of workers


def test_a_run_without_objectives_measures_no_energy_and_keeps_its_columns() -> None:
    result = library.evolve(SMALL, algorithm="afpo", workers=1)
    assert all(r["energy"] is None for r in result.measures.values())
    assert "hypervolume" not in result.curve[-1]


def test_a_run_stopped_before_the_normalised_hypervolume_goes_on(tmp_path: Path) -> None:
    """A run whose config and first generation were stored before ideals existed: the config
    loads with the defaults, the old row stays without the column, the new one has it."""
    stored = library.configure(SMALL, algorithm="nsga2", objectives=OBJECTIVES).to_json()
    stored["objectives"] = [
        {k: v for k, v in o.items() if k != "ideal"} for o in stored["objectives"]
    ]
    config = resolve(stored)
    evolution = Evolution.start(config)
    evolution.step(SerialEvaluator())
    first = replace(evolution.state.history[0], normalised_hypervolume=None)
    state = replace(evolution.state, history=[first])
    evolution = Evolution.resume(config, state, evolution.cache, measures=evolution.measures)
    evolution.step(SerialEvaluator())
    old, new = evolution.curve()
    assert "normalised_hypervolume" not in old and 0 < new["normalised_hypervolume"] <= 1
    whole = library.evolve({**SMALL, "generations": 2}, algorithm="nsga2", objectives=OBJECTIVES)
    assert new == whole.curve[1]  # the resumed generation is the uninterrupted one
    assert old == {k: v for k, v in whole.curve[0].items() if k != "normalised_hypervolume"}
    write_results(tmp_path, evolution)
    lines = (tmp_path / "curve.csv").read_text().splitlines()
    assert lines[1].endswith(",") and not lines[2].endswith(",")


def test_softevo_run_writes_the_pareto_columns(tmp_path: Path) -> None:
    out = tmp_path / "run"
    done = softevo(
        "run",
        "--preset",
        "quick",
        "--shape",
        "2x2x2",
        "--population",
        "6",
        "--generations",
        "2",
        "--duration",
        "1",
        "--algorithm",
        "afpo",
        "--objectives=speed,-cost_of_transport",
        "--workers",
        "1",
        "--out",
        str(out),
    )
    assert done.returncode == 0, done.stderr
    with (out / "curve.csv").open(encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert list(rows[0])[-3:] == ["hypervolume", "front_size", "normalised_hypervolume"]
    assert float(rows[-1]["hypervolume"]) > 0 and int(rows[-1]["front_size"]) >= 1
    assert 0 < float(rows[-1]["normalised_hypervolume"]) <= 1
    assert (out / "front.png").stat().st_size > 0
    assert (out / "hypervolume.png").stat().st_size > 0  # against the simulations run
    config, _, individuals = read_results(out)
    specs = resolve(config).objectives
    with (out / "front.csv").open(encoding="utf-8") as handle:
        front = [(int(r["generation"]), int(r["index"])) for r in csv.DictReader(handle)]
    everyone = front_values(specs, individuals)
    on_front = everyone[[(r["generation"], r["index"]) in front for r in individuals]]
    assert len(on_front) == len(front) >= 1
    for point in on_front:  # mutually non-dominated
        assert not any(pareto.dominates(other, point) for other in on_front)
    for point in everyone[~np.isnan(everyone).any(axis=1)]:  # the rest dominated or equal
        assert any(pareto.dominates(f, point) or (f == point).all() for f in on_front)


def test_softevo_run_resumed_gives_the_same_curve_and_front(tmp_path: Path) -> None:
    flags = [
        "--preset",
        "quick",
        "--shape",
        "2x2x2",
        "--population",
        "6",
        "--duration",
        "1",
        "--algorithm",
        "afpo",
        "--objectives=speed,-cost_of_transport",
        "--workers",
        "1",
    ]
    whole, part = tmp_path / "whole", tmp_path / "part"
    assert softevo("run", *flags, "--generations", "4", "--out", str(whole)).returncode == 0
    assert softevo("run", *flags, "--generations", "2", "--out", str(part)).returncode == 0
    assert softevo("run", "--resume", str(part), "--generations", "4").returncode == 0
    for name in ("curve.csv", "front.csv"):
        assert (part / name).read_text() == (whole / name).read_text()
