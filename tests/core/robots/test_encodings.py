"""Encodings: every genome becomes a robot file and back, hashes are stable, robots build."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from softevo.core.physics import simulate
from softevo.core.robots.encoding_registry import make_encoding
from softevo.core.robots.encodings import EncodingError
from softevo.core.robots.genome import Genome
from softevo.core.robots.robot_file import parse_robot, robot_to_json
from softevo.core.robots.settings import sim_settings

SIM = sim_settings({"duration": 0.2, "settle_time": 0.1})


@pytest.mark.parametrize(
    ("name", "shape"), [("voxel", (3, 2, 2)), ("cube-springs", (1, 1, 1)), ("spring", (2, 2, 1))]
)
def test_genome_to_robot_file_and_back(name: str, shape: tuple[int, int, int]) -> None:
    encoding = make_encoding(name, shape)
    rng = np.random.default_rng(3)
    for _ in range(20):
        genome = encoding.random(rng)
        encoding.check(genome)
        document = json.loads(json.dumps(robot_to_json(encoding.to_robot(genome, SIM))))
        assert document["format"] == "softevo.robot/1"
        again = encoding.from_robot(parse_robot(document))
        assert again == genome
        assert again.hash == genome.hash


def test_spring_encoding_gives_every_lattice_spring_its_own_material() -> None:
    encoding = make_encoding("spring", (2, 1, 1))
    n_voxels = 2
    all_soft = np.array([1, 1] + [0] * 50)  # SPRING_LABELS[0] == "soft"
    genome = encoding.genome(all_soft, (0.0, 0.0, 0.0))
    soft = simulate(encoding.to_robot(genome, SIM))[0]
    one_hard = all_soft.copy()
    one_hard[n_voxels + 3] = 1  # one spring hard: the robot differs from the all-soft one
    hard = simulate(encoding.to_robot(encoding.genome(one_hard, (0.0, 0.0, 0.0)), SIM))[0]
    assert soft.springs == hard.springs == 50
    assert not np.array_equal(soft.final_positions, hard.final_positions)


def test_genome_hash_is_stable_across_processes() -> None:
    genome = Genome("voxel", (0, 1, 2, 3, 4), (0.1, -0.5, 3.0))
    code = (
        "from softevo.core.robots.genome import Genome;"
        "print(Genome('voxel', (0, 1, 2, 3, 4), (0.1, -0.5, 3.0)).hash)"
    )
    other = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert other.stdout.strip() == genome.hash
    assert Genome("voxel", (0, 1, 2, 3, 4), (0.1, -0.5, 3.0000001)).hash != genome.hash


def test_bad_genomes_are_refused() -> None:
    encoding = make_encoding("voxel", (2, 1, 1))
    with pytest.raises(EncodingError, match="needs 2 discrete"):
        encoding.to_robot(Genome("voxel", (1,), (0.0, 0.0, 0.0)), SIM)
    with pytest.raises(EncodingError, match="alphabet"):
        encoding.to_robot(Genome("voxel", (1, 9), (0.0, 0.0, 0.0)), SIM)
    with pytest.raises(EncodingError, match="encoding 'spring'"):
        encoding.to_robot(Genome("spring", (1, 1), (0.0, 0.0, 0.0)), SIM)
    with pytest.raises(EncodingError, match="unknown encoding"):
        make_encoding("tree", (1, 1, 1))
