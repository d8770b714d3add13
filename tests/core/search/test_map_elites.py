"""MAP-Elites: the archive's rules, the descriptors of the simulated body, and runs that give the
same archive whatever evaluates them."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from softevo.core.config import ConfigError, resolve
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import PoolEvaluator, SerialEvaluator
from softevo.core.robots.genome import Genome
from softevo.core.robots.lattice import largest_component
from softevo.core.search.archive import Archive
from softevo.core.search.descriptors import describe, largest_group
from softevo.core.search.state import StrategyState

QD = {
    "preset": "quick",
    "algorithm": "map-elites",
    "descriptors": ["voxels", "actuated"],
    "bins": [4, 4],
    "population": 10,
    "generations": 5,
    "seed": 7,
    "sim": {"duration": 1.5},
}


def genome(*labels: int) -> Genome:
    return Genome("voxel", tuple(labels), (0.0, 0.0, 0.0))


def test_the_archive_keeps_the_better_elite_per_cell_whatever_the_order() -> None:
    offers = [  # (values, fitness, genome): three share a cell, two tie on fitness
        ((0.10, 0.10), 0.5, genome(1, 2)),
        ((0.12, 0.05), 0.9, genome(2, 2)),
        ((0.11, 0.15), 0.9, genome(3, 1)),
        ((0.90, 0.90), 0.2, genome(1, 1)),
        ((0.95, 0.99), float("nan"), genome(4, 4)),
        ((1.0, 0.0), -0.1, genome(3, 3)),
    ]
    results = set()
    for order in itertools.permutations(range(len(offers))):
        archive = Archive(("voxels", "actuated"), (4, 4))
        for i in order:
            values, fitness, g = offers[i]
            archive.add(values, fitness, 0, i, g)
        results.add(json.dumps(archive.to_json()))
    assert len(results) == 1
    archive = Archive.from_json(json.loads(results.pop()))
    assert sorted(archive.elites) == [(0, 0), (3, 0), (3, 3)]  # 1.0 is in the top cell
    winner = min(genome(2, 2), genome(3, 1), key=lambda g: g.hash)  # the tie: smaller hash
    assert archive.elites[(0, 0)].genome == winner and archive.elites[(0, 0)].fitness == 0.9
    assert archive.coverage == 3 / 16
    assert archive.qd_score == pytest.approx(0.9 + 0.2 - 0.1)


def test_largest_group_is_the_lattices_largest_component() -> None:
    rng = np.random.default_rng(3)
    for box in ((4, 4, 4), (3, 3, 6), (9, 9, 2), (2, 7, 3), (1, 1, 5)):
        for density in (0.3, 0.5, 0.8):
            filled = rng.random(int(np.prod(box))) < density
            if not filled.any():
                continue
            mask = sum(1 << int(i) for i in np.flatnonzero(filled))
            expected = largest_component(filled, box)
            assert largest_group(mask, box) == sum(1 << int(i) for i in np.flatnonzero(expected))


def test_descriptors_describe_the_simulated_body_not_the_cut_off_voxels() -> None:
    # 3x1x2: bottom row soft, hard, sine; top row empty, empty, neg_sine; plus nothing cut off
    labels = [1, 2, 3, 0, 0, 4]
    assert describe(["voxels", "actuated", "soft", "height"], labels, (3, 1, 2)) == (
        4 / 6,
        2 / 4,
        1 / 4,
        1.0,
    )
    # a lone voxel in the far corner is not part of the body: one voxel, one layer of two
    assert describe(["voxels", "height"], [3, 0, 0, 0, 0, 0, 0, 2], (2, 2, 2)) == (1 / 8, 0.5)
    assert describe(["voxels"], [0] * 8, (2, 2, 2)) == ()


def run(request: dict, evaluator) -> Evolution:
    evolution = Evolution.start(resolve(request))
    evolution.run(evaluator)
    return evolution


def test_the_same_seed_gives_the_same_archive_and_curve_on_one_and_two_processes() -> None:
    serial = run(QD, SerialEvaluator())
    with PoolEvaluator(1) as one, PoolEvaluator(2) as two:
        runs = [run(QD, one), run(QD, two)]
    for other in runs:
        assert other.state.archive.to_json() == serial.state.archive.to_json()
        assert other.curve() == serial.curve()
    rows = serial.curve()
    assert all(0 < row["coverage"] <= 1 for row in rows)
    assert [row["coverage"] for row in rows] == sorted(row["coverage"] for row in rows)
    assert rows[-1]["qd_score"] >= rows[0]["qd_score"] > 0
    assert any(i.operator.startswith("elite-") for i in serial.state.previous)


def test_a_run_resumed_from_its_json_state_ends_with_the_same_archive() -> None:
    whole = run(QD, SerialEvaluator())
    half = Evolution.start(resolve(QD))
    with SerialEvaluator() as evaluator:
        for _ in range(2):
            half.step(evaluator)
        half.state = StrategyState.from_json(json.loads(json.dumps(half.state.to_json())))
        half.cache.clear()  # a takeover rebuilds its cache; the fitness is the same
        half.run(evaluator)
    assert half.state.archive.to_json() == whole.state.archive.to_json()
    assert [r["best"] for r in half.curve()] == [r["best"] for r in whole.curve()]


def test_a_ga_with_descriptors_breeds_as_without_and_keeps_an_archive_beside() -> None:
    plain = {**QD, "algorithm": "ga", "descriptors": [], "bins": []}
    alone, beside = run(plain, SerialEvaluator()), run({**QD, "algorithm": "ga"}, SerialEvaluator())
    assert [r["best"] for r in alone.curve()] == [r["best"] for r in beside.curve()]
    assert "coverage" not in alone.curve()[0] and "archive" not in alone.state.to_json()
    assert beside.curve()[-1]["coverage"] > 0


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"descriptors": []}, "map-elites needs at least one descriptor"),
        ({"descriptors": ["voxels", "legs"]}, "unknown ['legs']"),
        ({"bins": [4]}, "bins: one count per descriptor"),
        ({"bins": [200, 200]}, "40000 cells"),
        ({"preset": "paper-cube"}, "only for the voxel encodings"),
    ],
)
def test_a_bad_archive_is_refused_naming_the_field(change: dict, message: str) -> None:
    request = {**QD, **change}
    if change.get("preset") == "paper-cube":
        request.pop("sim")
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
        resolve(request)
