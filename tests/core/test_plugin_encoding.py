"""A third-party encoding, installed as a package of one module through the entry-point group
`softevo.encodings`, runs with any strategy and brings its own variation: no file of softevo
changes for it (before, the cppn encoding was named in config.py, encodings.py, variation.py,
stats.py and map_elites.py)."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from softevo import library
from softevo.core.config import ConfigError
from softevo.core.robots.encoding_registry import GROUP, encodings

#: The whole plug-in: one module. Genes: one bit per voxel of the box (filled, and then a muscle
#: in phase), and the three actuation genes; its own variation flips bits.
MODULE = """
import numpy as np

from softevo.core.robots.encodings import ACTUATION_BOUNDS, Encoding, Segment, Variation
from softevo.core.robots.genome import Genome
from softevo.core.robots.robot import Actuation, VoxelRobot


class Flips(Variation):
    def mate(self, rates, first, second, rng):
        return False, [(self.mutate(rates, first, rng), "flip"), (second, "copy")]

    def mutate(self, rates, genome, rng):
        bits = list(genome.discrete)
        index = int(rng.integers(len(bits)))
        bits[index] = 1 - bits[index]
        return Genome("bits", tuple(bits), genome.real)


class Bits(Encoding):
    name = "bits"
    describable = True
    variation = Flips()

    def __init__(self, shape):
        self.shape = shape
        self.segments = (Segment(0, int(np.prod(shape)), 2),)
        self.real_bounds = ACTUATION_BOUNDS

    def labels(self, genome):
        return tuple(3 * bit for bit in genome.discrete)  # empty or sine (LABELS' indices)

    def to_robot(self, genome, sim):
        labels = tuple("sine" if bit else "empty" for bit in genome.discrete)
        return VoxelRobot(self.shape, labels, Actuation(*genome.real), sim)

    def from_robot(self, robot):
        raise ValueError("not read back")
"""
RUN = {
    "preset": "quick",
    "encoding": "bits",
    "shape": [2, 2, 1],
    "population": 4,
    "generations": 2,
    "selection": "tournament",
    "seed": 5,
    "sim": {"duration": 0.3, "settle_time": 0.1},
}


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The module installed the way pip installs one: it and a dist-info with its entry point."""
    root = tmp_path_factory.mktemp("site")
    (root / "bits_encoding.py").write_text(MODULE)
    dist = root / "bits_encoding-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: bits-encoding\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text(f"[{GROUP}]\nbits = bits_encoding:Bits\n")
    sys.path.insert(0, str(root))
    encodings.cache_clear()
    yield root
    sys.path.remove(str(root))
    sys.modules.pop("bits_encoding", None)
    encodings.cache_clear()


@pytest.mark.parametrize("algorithm", ["ga", "steady-state"])
def test_an_installed_encoding_runs_with_its_own_variation(site: Path, algorithm: str) -> None:
    extra = {"descriptors": ["voxels"], "bins": [4]} if algorithm == "map-elites" else {}
    result = library.evolve({**RUN, "algorithm": algorithm, **extra}, workers=1)
    assert len(result.curve) == 2
    assert result.state["best"]["genome"]["encoding"] == "bits"
    # the children came from the plug-in's own operators (the runs may breed in a worker)
    operators = {individual["operator"] for individual in result.state["previous"]}
    assert any(operator.endswith("flip") for operator in operators), operators


def test_an_encoding_not_installed_is_refused_with_the_installed_ones(site: Path) -> None:
    with pytest.raises(ConfigError, match=r"unknown encoding 'nope' \(bits, cppn, "):
        library.configure({**RUN, "encoding": "nope"})
