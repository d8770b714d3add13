"""The `voxel-phase` encoding: every actuated voxel's own phase and amplitude, the paper's sine
and neg_sine as phases 0 and pi, old robot files unchanged, genes that travel with their label."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from softevo.core.config import resolve
from softevo.core.evolution import Evolution
from softevo.core.physics import simulate
from softevo.core.physics.evaluation import PoolEvaluator, SerialEvaluator
from softevo.core.robots.encoding_registry import make_encoding
from softevo.core.robots.encodings import VoxelPhaseEncoding
from softevo.core.robots.robot import Actuation, VoxelRobot, build_mechanics
from softevo.core.robots.robot_file import RobotFileError, load_robot, parse_robot, robot_to_json
from softevo.core.robots.settings import SimSettings
from softevo.core.search.configured import Individual, StrategySettings
from softevo.core.search.variation import mate

EXAMPLES = sorted((Path(__file__).resolve().parents[3] / "examples").glob("*.json"))
SIM = SimSettings.model_validate({"duration": 1.0, "settle_time": 0.3})


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_an_old_robot_file_loads_unchanged(path: Path) -> None:
    robot = load_robot(path)
    document = robot_to_json(robot)
    assert "phases" not in document and "amplitudes" not in document
    assert robot_to_json(parse_robot(json.loads(json.dumps(document)))) == document


def test_the_papers_sine_and_neg_sine_are_phases_zero_and_pi() -> None:
    rng = np.random.default_rng(6)
    labels = tuple(rng.choice(["empty", "soft", "hard", "sine", "neg_sine"], 27).tolist())
    paper = VoxelRobot((3, 3, 3), labels, Actuation(0.2, 0.9, -1.3), SIM)
    genome = VoxelPhaseEncoding((3, 3, 3)).from_robot(paper)  # an old robot, the new encoding
    as_sine = tuple("sine" if label == "neg_sine" else label for label in labels)
    pi = [math.pi if label == "neg_sine" else 0.0 for label in labels]
    real = (*genome.real[: 2 + 27], *pi)
    phased = VoxelPhaseEncoding((3, 3, 3)).to_robot(
        VoxelPhaseEncoding((3, 3, 3)).genome(
            np.array(
                [
                    labels.index(x)
                    if False
                    else ["empty", "soft", "hard", "sine", "neg_sine"].index(x)
                    for x in as_sine
                ]
            ),
            np.array(real),
        ),
        SIM,
    )
    old, new = build_mechanics(paper), build_mechanics(phased)
    for name in ("stiffness", "rest_length", "amp_sin", "amp_cos"):
        np.testing.assert_allclose(getattr(new, name), getattr(old, name), rtol=0, atol=1e-15)
    assert math.isclose(simulate(phased)[0].speed, simulate(paper)[0].speed, rel_tol=1e-9)


def test_a_voxels_own_phase_changes_the_gait() -> None:
    labels = ("sine", "hard", "sine", "soft")
    base = VoxelRobot((4, 1, 1), labels, Actuation(0.1, 0.8, 0.0), SIM, (0.0,) * 4, (0.8,) * 4)
    turned = VoxelRobot((4, 1, 1), labels, base.actuation, SIM, (0.0, 0.0, 2.0, 0.0), (0.8,) * 4)
    assert simulate(base)[0].speed != simulate(turned)[0].speed


def test_a_co_designed_robot_file_round_trips_and_bad_ones_name_the_field() -> None:
    encoding = VoxelPhaseEncoding((3, 2, 2))
    genome = encoding.random(np.random.default_rng(3))
    robot = encoding.to_robot(genome, SIM)
    document = robot_to_json(robot)
    actuated = [v in ("sine", "neg_sine") for v in document["voxels"]]
    assert [p is not None for p in document["phases"]] == actuated
    again = parse_robot(json.loads(json.dumps(document)))
    assert robot_to_json(again) == document
    assert np.array_equal(build_mechanics(again).amp_cos, build_mechanics(robot).amp_cos)
    first = actuated.index(True)
    for change, words in (
        ({"phases": [0.0]}, "phases: expected 12 values"),
        ({"phases": [None] * 12}, f"phases.{first}: a number is needed"),
        ({"amplitudes": [5.0 if a else None for a in actuated]}, f"amplitudes.{first}: 5.0 is"),
        ({"phases": [0.0] * 12}, "must be null on a"),
    ):
        with pytest.raises(RobotFileError, match=words):
            parse_robot({**document, **change})


def test_crossover_carries_a_voxels_phase_and_amplitude_with_its_label() -> None:
    encoding = make_encoding("voxel-phase", (4, 2, 1))
    n = 8
    first = encoding.genome(np.zeros(n, dtype=int), np.array([0.1, 0.2, *[0.3] * n, *[-1.0] * n]))
    second = encoding.genome(np.full(n, 3), np.array([-0.1, -0.2, *[-0.4] * n, *[2.0] * n]))
    config = StrategySettings(crossover_probability=1.0, mutation_probability=0.0)
    rng = np.random.default_rng(1)
    swapped = 0
    for _ in range(50):
        pair = (Individual(first, "x"), Individual(second, "x"))
        children = mate(config, encoding, pair, (0, 1), rng)
        for child in children:
            amplitudes, phases = child.genome.real[2 : 2 + n], child.genome.real[2 + n :]
            for label, amplitude, phase in zip(
                child.genome.discrete, amplitudes, phases, strict=True
            ):
                assert (amplitude, phase) == ((0.3, -1.0) if label == 0 else (-0.4, 2.0))
            swapped += len(set(child.genome.discrete)) == 2
    assert swapped > 0  # crossovers that mix the parents happened


@pytest.mark.parametrize("algorithm", ["ga", "random", "map-elites"])
def test_voxel_phase_runs_give_the_same_curve_on_one_and_two_processes(algorithm: str) -> None:
    request = {
        "preset": "quick",
        "encoding": "voxel-phase",
        "algorithm": algorithm,
        "seed": 3,
        "population": 8,
        "generations": 3,
        "sim": {"duration": 1.0},
        **(
            {"descriptors": ["voxels", "actuated"], "bins": [4, 4]}
            if algorithm == "map-elites"
            else {}
        ),
    }
    serial = Evolution.start(resolve(request))
    serial.run(SerialEvaluator())
    with PoolEvaluator(2) as pool:
        parallel = Evolution.start(resolve(request))
        parallel.run(pool)
    assert parallel.curve() == serial.curve()
    best, _, _ = serial.best_robot()
    assert best.phases is not None and len(best.phases) == 27
