"""The `cppn` encoding (`softevo.core.robots.cppn`'s network queried at every voxel), registered
in the entry-point group `softevo.encodings` like every encoding, built in or a user's: the
network and its NEAT variation are its own modules, so search never names it."""

from __future__ import annotations

import math

import numpy as np

from softevo.core.robots.cppn import (
    ACTIVATIONS,
    N_IN,
    OUTPUT_IDS,
    ROBOT_BOUNDS,
    WEIGHT,
    Connection,
    Network,
    box_inputs,
    innovation,
)
from softevo.core.robots.cppn_variation import NeatVariation, mutate_network
from softevo.core.robots.encodings import Encoding, EncodingError
from softevo.core.robots.genome import Genome
from softevo.core.robots.robot import GENE_BOUNDS, LABELS, Actuation, Robot, VoxelRobot
from softevo.core.robots.settings import SimSettings


class CppnEncoding(Encoding):
    """Genes <-> a CPPN; the robot is the network queried at every voxel of `shape`. Brings
    its own variation (NEAT operators), which the strategies use, and reads diversity as the
    connections the networks share."""

    name = "cppn"
    describable = True
    variation = NeatVariation()
    voxel_reals = 0
    #: Stored bytes of a genome, for the service's cost estimate (`softevo.api.cost`): a network
    #: of about 60 connections (each ~40 characters of integers and ~20 of weight).
    genome_bytes = 4000

    def __init__(self, shape: tuple[int, int, int]) -> None:
        self.shape = shape
        self.inputs = box_inputs(shape)
        self.segments = ()
        self.real_bounds = ROBOT_BOUNDS  # a and c; the weights are bounded by WEIGHT

    @property
    def n_discrete(self) -> int:  # the genome's length varies with its network
        return 0

    def real_bounds_of(self, genome: Genome) -> np.ndarray:
        weights = np.tile([-WEIGHT, WEIGHT], (len(genome.real) - 2, 1))
        return np.concatenate([ROBOT_BOUNDS, weights.reshape(-1, 2)])

    def check(self, genome: Genome) -> None:
        Network.from_genome(genome)

    def random(self, rng: np.random.Generator) -> Genome:
        """Every input joined to every output (uniform weights, random activations), then a
        few NEAT mutations, so the first population already differs in structure."""
        nodes = tuple((o, int(rng.integers(len(ACTIVATIONS)))) for o in OUTPUT_IDS)
        pairs = sorted((innovation(i, o), i, o) for i in range(N_IN) for o in OUTPUT_IDS)
        weights = rng.uniform(-WEIGHT, WEIGHT, len(pairs))
        links = tuple(
            Connection(k, i, o, True, float(w)) for (k, i, o), w in zip(pairs, weights, strict=True)
        )
        a, c = rng.uniform(ROBOT_BOUNDS[:, 0], ROBOT_BOUNDS[:, 1])
        network = Network(nodes, links, float(a), float(c))
        for _ in range(int(rng.integers(0, 4))):
            network = mutate_network(network, rng)
        return network.genome()

    def decode(
        self, genome: Genome
    ) -> tuple[tuple[str, ...], tuple[float, ...], tuple[float, ...], Actuation]:
        """Labels, phases, amplitudes and the robot's actuation of a genome's body."""
        network = Network.from_genome(genome)
        presence, muscle, stiffness, phase, amplitude = network.query(self.inputs)
        labels = np.where(muscle > 0, "sine", np.where(stiffness > 0, "hard", "soft"))
        labels = np.where(presence > 0, labels, "empty")
        low, high = GENE_BOUNDS["b"]
        amplitudes = low + (high - low) * (np.tanh(amplitude) + 1) / 2
        phases = math.pi * np.tanh(phase)
        return (
            tuple(labels.tolist()),
            tuple(phases.tolist()),
            tuple(amplitudes.tolist()),
            Actuation(network.a, 0.0, network.c),
        )

    def labels(self, genome: Genome) -> tuple[int, ...]:
        """Label index of every voxel of the decoded body (what the descriptors read)."""
        return tuple(LABELS.index(label) for label in self.decode(genome)[0])

    def to_robot(self, genome: Genome, sim: SimSettings) -> VoxelRobot:
        labels, phases, amplitudes, actuation = self.decode(genome)
        return VoxelRobot(self.shape, labels, actuation, sim, phases, amplitudes)

    def from_robot(self, robot: Robot) -> Genome:
        raise EncodingError(
            "a cppn genome cannot be read back from its body (many networks "
            "grow one body); its robot file is a voxel-phase robot"
        )

    def diversity(self, genomes: list[Genome]) -> float:
        return network_diversity(genomes) if len(genomes) >= 2 else 0.0


def network_diversity(genomes: list[Genome]) -> float:
    """Mean pairwise Jaccard distance of the genomes' sets of enabled connections (innovation
    numbers): the `cppn` reading of a generation's diversity (0 alike, 1 nothing shared)."""
    sets = [
        {link.innovation for link in Network.from_genome(g).connections if link.enabled}
        for g in genomes
    ]
    total, pairs = 0.0, 0
    for i, first in enumerate(sets):
        for second in sets[i + 1 :]:
            union = len(first | second)
            total += 1 - len(first & second) / union if union else 0.0
            pairs += 1
    return total / pairs
