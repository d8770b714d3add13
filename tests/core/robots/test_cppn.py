"""The `cppn` encoding: decoding, activations, NEAT operators, and runs of every strategy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from softevo import library
from softevo.core.config import ConfigError, resolve
from softevo.core.robots.cppn import (
    ACTIVATIONS,
    OUTPUT_IDS,
    Network,
    activate,
    innovation,
    split_node,
)
from softevo.core.robots.cppn_encoding import CppnEncoding
from softevo.core.robots.cppn_variation import _add_connection, _add_node, crossover
from softevo.core.robots.encoding_registry import make_encoding
from softevo.core.robots.encodings import EncodingError
from softevo.core.robots.genome import Genome
from softevo.core.robots.robot_file import parse_robot, robot_to_json
from softevo.core.robots.settings import SimSettings
from softevo.core.search.configured import StrategySettings
from softevo.core.search.state import Individual
from softevo.core.search.variation import mate, mutant

SIM = SimSettings(duration=0.3, settle_time=0.1)


def _genomes(n: int, seed: int = 1, shape: tuple[int, int, int] = (3, 3, 3)) -> list[Genome]:
    encoding, rng = CppnEncoding(shape), np.random.default_rng(seed)
    return [encoding.random(rng) for _ in range(n)]


def test_random_genomes_and_their_bodies_are_the_seeds() -> None:
    first, second = _genomes(4), _genomes(4)
    assert [g.hash for g in first] == [g.hash for g in second]
    assert _genomes(4, seed=2)[0].hash != first[0].hash
    encoding = make_encoding("cppn", (3, 3, 3))
    robots = [encoding.to_robot(g, SIM) for g in first]
    assert [r.voxels for r in robots] == [encoding.to_robot(g, SIM).voxels for g in second]
    assert len({r.voxels for r in robots}) > 1  # networks differ, and so do bodies
    for robot in robots:
        assert set(robot.voxels) <= {"empty", "soft", "hard", "sine"}
        assert all(-math.pi <= p <= math.pi for p in robot.phases)


def test_the_genome_round_trips_through_json_and_a_bad_one_is_refused() -> None:
    genome = _genomes(1)[0]
    again = Genome.from_json(genome.to_json())
    assert again.hash == genome.hash and Network.from_genome(again) == Network.from_genome(genome)
    discrete = list(genome.discrete)
    discrete[-4] += 1  # the first connection's innovation no longer its (from, to) pair's
    with pytest.raises(EncodingError, match="innovation"):
        CppnEncoding((2, 2, 2)).check(Genome("cppn", tuple(discrete), genome.real))
    with pytest.raises(EncodingError, match="gene counts"):
        CppnEncoding((2, 2, 2)).check(Genome("cppn", genome.discrete, genome.real[:-1]))
    with pytest.raises(EncodingError, match="gene counts"):  # more nodes than genes
        CppnEncoding((2, 2, 2)).check(Genome("cppn", (5, 5, 0, 6, 0, 7, 0), (0.0,)))


def test_activations_are_the_fields() -> None:
    x = np.array([-2.0, 0.0, 1.0])
    expected = {
        "sine": np.sin(x),
        "gaussian": np.exp(-x * x),
        "sigmoid": 1 / (1 + np.exp(-x)),
        "tanh": np.tanh(x),
        "abs": np.abs(x),
        "identity": x,
    }
    assert set(ACTIVATIONS) == set(expected)
    for name, values in expected.items():
        np.testing.assert_allclose(activate(name, x), values)
    with pytest.raises(EncodingError, match="activation"):
        activate("relu", x)


def test_innovations_are_the_pairs_and_a_split_makes_a_valid_network() -> None:
    assert innovation(0, 5) == innovation(0, 5) != innovation(5, 0)
    network = Network.from_genome(_genomes(1, seed=3)[0])
    rng = np.random.default_rng(0)
    grown = _add_node(network, rng)
    assert grown is not None
    new = set(dict(grown.nodes)) - set(dict(network.nodes))
    (node,) = new
    split = next(ln for ln in network.connections if split_node(ln.source, ln.target) == node)
    links = {(ln.source, ln.target): ln for ln in grown.connections}
    assert not links[split.source, split.target].enabled
    assert links[split.source, node].weight == 1.0
    assert links[node, split.target].weight == split.weight
    Network.from_genome(grown.genome())  # valid: sorted, acyclic, innovations of their pairs
    joined = _add_connection(grown, rng)
    assert joined is not None and len(joined.connections) == len(grown.connections) + 1
    joined.order()  # no cycle


def test_crossover_aligns_connections_by_innovation() -> None:
    rng = np.random.default_rng(5)
    base, other = (Network.from_genome(g) for g in _genomes(2, seed=4))
    base = _add_node(base, rng) or base
    child = crossover(base, other, rng)
    assert [ln.innovation for ln in child.connections] == [ln.innovation for ln in base.connections]
    theirs = {ln.innovation: ln for ln in other.connections}
    took = 0
    for mine, got in zip(base.connections, child.connections, strict=True):
        assert got in (mine, theirs.get(mine.innovation))
        took += got is not mine
    assert took > 0  # matching genes came from the other parent too
    assert [n for n, _ in child.nodes] == [n for n, _ in base.nodes]


def test_mate_and_mutant_draw_only_from_the_generator() -> None:
    config = StrategySettings(mutation_probability=0.5, mutation_genes=2)
    encoding = CppnEncoding((3, 3, 3))
    pair = tuple(Individual(g, "random") for g in _genomes(2))
    runs = [mate(config, encoding, pair, (0, 1), np.random.default_rng(9)) for _ in range(2)]
    assert [c.genome.hash for c in runs[0]] == [c.genome.hash for c in runs[1]]
    for child in runs[0]:
        encoding.check(child.genome)
    one = mutant(config, encoding, pair[0], 0, np.random.default_rng(9))
    assert one.genome.hash != pair[0].genome.hash and one.parents == (0,)


def test_the_robot_file_of_a_cppn_individual_simulates() -> None:
    encoding = CppnEncoding((3, 3, 2))
    genomes = _genomes(8, shape=(3, 3, 2))
    genome = next(g for g in genomes if "sine" in encoding.to_robot(g, SIM).voxels)
    document = robot_to_json(encoding.to_robot(genome, SIM))
    assert document["format"] == "softevo.robot/1" and len(document["voxels"]) == 18
    result = library.simulate(document)
    assert math.isfinite(result["speed"]) and result["masses"] > 0 and result["stable"]
    assert parse_robot(document).voxels == encoding.to_robot(genome, SIM).voxels


@pytest.mark.parametrize("algorithm", ["ga", "random", "hillclimb", "map-elites", "nsga2", "afpo"])
def test_every_strategy_runs_with_cppn(algorithm: str) -> None:
    result = library.evolve(
        preset="quick",
        encoding="cppn",
        shape=[2, 2, 2],
        population=4,
        generations=2,
        seed=1,
        algorithm=algorithm,
        sim={"duration": 0.3, "settle_time": 0.1},
        workers=1,
    )
    assert len(result.curve) == 2 and result.best is not None
    assert len(result.best["voxels"]) == 8


def test_configs_name_the_cppn_settings() -> None:
    config = resolve({"preset": "cppn-8x8x8"})
    assert config.encoding == "cppn" and config.shape == (8, 8, 8)
    resolve({"preset": "quick", "encoding": "cppn", "descriptors": ["voxels"], "bins": [4]})
    with pytest.raises(ConfigError, match="encoding"):
        resolve({"preset": "quick", "encoding": "cppn2"})
    assert OUTPUT_IDS == (5, 6, 7, 8, 9)
