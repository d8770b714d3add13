"""The `cppn` encoding: a compositional pattern-producing network (Cheney et al. 2013) queried
at every voxel of the bounding box, decoded into a co-design voxel robot (`VoxelRobot` with
per-voxel phases and amplitudes), so robot files carry the decoded body and everything that
reads robot files works unchanged.

Inputs (ids 0-4): x, y, z (voxel centres scaled to [-1, 1]), the distance to the box's centre
(scaled to [0, 1]) and a bias of 1. Outputs (ids 5-9): presence (empty unless > 0), muscle
(actuated if > 0), stiffness (hard if > 0, else soft), phase (pi tanh, rad) and amplitude (the
paper's b bounds through tanh). Each output is taken from the middle of its activation's range
(0 for sine, tanh and identity; 0.5 for sigmoid, Gaussian and abs), so no activation fills or
empties every box. Actuated voxels are labelled `sine` with their own phase and amplitude.

This module holds the network; its NEAT variation is `softevo.core.robots.cppn_variation` and
the encoding that joins the two, a plug-in like any other, `softevo.core.robots.cppn_encoding`.

This module holds the network; its NEAT variation is `softevo.core.robots.cppn_variation` and
the encoding that joins the two, a plug-in like any other, `softevo.core.robots.cppn_encoding`.

The network is packed into a `Genome`: discrete genes `[n_nodes, (id, activation) per node,
(innovation, from, to, enabled) per connection]`, real genes `[a, c, weight per connection]`.
Innovation numbers and hidden node ids are hashes of (from, to) pairs, so one structural change
gets one number in every lineage, on any worker count and after a resume, with no counter.
`Genome.hash` stays the hash of the network: two networks that grow one body are two genomes
(each simulated once; the body decides their fitness, so they score alike).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass

import numpy as np

from softevo.core.robots.encodings import EncodingError
from softevo.core.robots.genome import Genome
from softevo.core.robots.robot import GENE_BOUNDS

ACTIVATIONS = ("sine", "gaussian", "sigmoid", "tanh", "abs", "identity")
#: Where each activation's output is cut when it feeds an output (the middle of its range).
_MIDDLE = {"sine": 0.0, "gaussian": 0.5, "sigmoid": 0.5, "tanh": 0.0, "abs": 0.5, "identity": 0.0}
INPUTS = ("x", "y", "z", "d", "bias")
OUTPUTS = ("presence", "muscle", "stiffness", "phase", "amplitude")
N_IN, N_OUT = len(INPUTS), len(OUTPUTS)
OUTPUT_IDS = tuple(range(N_IN, N_IN + N_OUT))
#: Bounds of a connection weight, and of the actuation genes a and c every robot carries.
WEIGHT = 3.0
ROBOT_BOUNDS = np.array([GENE_BOUNDS["a"], GENE_BOUNDS["c"]])
#: Chances of the NEAT mutations (one per mutation): weights, a node, a connection, an
#: activation, the robot's a and c.
MUTATIONS = (
    ("weights", 0.5),
    ("node", 0.15),
    ("connection", 0.15),
    ("activation", 0.1),
    ("actuation", 0.1),
)
#: Step of a perturbed weight, and the chance each weight is perturbed.
WEIGHT_SIGMA, WEIGHT_RATE = 0.5, 0.5


def _key(kind: str, source: int, target: int) -> int:
    """A 40-bit number of a (from, to) pair: the innovation of a connection ("c") or the id of
    the node that splits it ("n"). Collisions are negligible (2^-40 a pair)."""
    digest = hashlib.sha256(f"{kind}{source}>{target}".encode()).digest()
    return int.from_bytes(digest[:5], "big") + 64  # above every input and output id


def innovation(source: int, target: int) -> int:
    return _key("c", source, target)


def split_node(source: int, target: int) -> int:
    return _key("n", source, target)


@dataclass(frozen=True)
class Connection:
    innovation: int
    source: int
    target: int
    enabled: bool
    weight: float


@dataclass(frozen=True)
class Network:
    """A feed-forward CPPN: `nodes` (id, activation index) of outputs and hidden nodes sorted
    by id, `connections` sorted by innovation, and the robot's actuation genes a and c."""

    nodes: tuple[tuple[int, int], ...]
    connections: tuple[Connection, ...]
    a: float = 0.0
    c: float = 0.0

    def genome(self) -> Genome:
        discrete = [len(self.nodes)]
        for node, activation in self.nodes:
            discrete += [node, activation]
        for link in self.connections:
            discrete += [link.innovation, link.source, link.target, int(link.enabled)]
        real = [self.a, self.c, *(link.weight for link in self.connections)]
        return Genome("cppn", tuple(discrete), tuple(float(v) for v in real))

    @classmethod
    def from_genome(cls, genome: Genome) -> Network:
        """The network of a genome, refusing a malformed one with one line."""
        d, r = genome.discrete, genome.real
        if genome.encoding != "cppn":
            raise EncodingError(f"genome of encoding {genome.encoding!r}, expected 'cppn'")
        n_nodes = d[0] if d else -1
        n_links = (len(d) - 1 - 2 * n_nodes) / 4
        if n_nodes < N_OUT or n_links < 0 or n_links != int(n_links) or len(r) != 2 + n_links:
            raise EncodingError("cppn genome: its gene counts do not describe a network")
        nodes = tuple((d[1 + 2 * i], d[2 + 2 * i]) for i in range(n_nodes))
        base = 1 + 2 * n_nodes
        links = tuple(
            Connection(
                d[base + 4 * i],
                d[base + 4 * i + 1],
                d[base + 4 * i + 2],
                bool(d[base + 4 * i + 3]),
                r[2 + i],
            )
            for i in range(int(n_links))
        )
        network = cls(nodes, links, r[0], r[1])
        network.validate()
        return network

    def validate(self) -> None:
        ids = [node for node, _ in self.nodes]
        if ids[:N_OUT] != list(OUTPUT_IDS) or ids != sorted(set(ids)):
            raise EncodingError("cppn genome: nodes must be the outputs, then hidden ids, sorted")
        if any(not 0 <= act < len(ACTIVATIONS) for _, act in self.nodes):
            raise EncodingError("cppn genome: an activation out of range")
        known = set(ids) | set(range(N_IN))
        innovations = [link.innovation for link in self.connections]
        if innovations != sorted(set(innovations)):
            raise EncodingError("cppn genome: connections must be sorted by innovation, once each")
        for link in self.connections:
            if link.innovation != innovation(link.source, link.target):
                raise EncodingError("cppn genome: an innovation that is not its (from, to) pair's")
            if link.source not in known or link.target not in ids or link.source in OUTPUT_IDS:
                raise EncodingError("cppn genome: a connection between unknown nodes")
            if not abs(link.weight) <= WEIGHT:
                raise EncodingError(f"cppn genome: a weight outside [-{WEIGHT:g}, {WEIGHT:g}]")
        if not all(
            lo <= v <= hi
            for v, (lo, hi) in zip((self.a, self.c), ROBOT_BOUNDS.tolist(), strict=True)
        ):
            raise EncodingError("cppn genome: a or c outside its bounds")
        self.order()  # refuses a cycle

    def order(self) -> list[int]:
        """Nodes (outputs and hidden) in an order where every node comes after its sources."""
        incoming: dict[int, set[int]] = {node: set() for node, _ in self.nodes}
        for link in self.connections:
            if link.enabled:
                incoming[link.target].add(link.source)
        done: set[int] = set(range(N_IN))
        order: list[int] = []
        while len(order) < len(incoming):
            ready = [n for n in sorted(incoming) if n not in done and incoming[n] <= done]
            if not ready:
                raise EncodingError("cppn genome: its connections make a cycle")
            order += ready
            done.update(ready)
        return order

    def query(self, inputs: np.ndarray) -> np.ndarray:
        """Outputs [N_OUT, V] at V points (`inputs` [N_IN, V]), each taken from the middle of
        its activation's range."""
        values = dict(enumerate(inputs))
        activation = dict(self.nodes)
        links = [link for link in self.connections if link.enabled]
        zero = np.zeros(inputs.shape[1])
        for node in self.order():
            total = sum(
                (link.weight * values[link.source] for link in links if link.target == node), zero
            )
            values[node] = activate(ACTIVATIONS[activation[node]], total)
        return np.array([values[o] - _MIDDLE[ACTIVATIONS[activation[o]]] for o in OUTPUT_IDS])


def activate(name: str, x: np.ndarray) -> np.ndarray:
    """The field's CPPN activations (Gaussian exp(-x^2), logistic sigmoid)."""
    if name == "sine":
        return np.sin(x)
    if name == "gaussian":
        return np.exp(-np.square(x))
    if name == "sigmoid":
        return 1.0 / (1.0 + np.exp(-np.clip(x, -60.0, 60.0)))
    if name == "tanh":
        return np.tanh(x)
    if name == "abs":
        return np.abs(x)
    if name == "identity":
        return np.asarray(x, dtype=np.float64)
    raise EncodingError(f"unknown activation {name!r} (one of {', '.join(ACTIVATIONS)})")


def box_inputs(shape: tuple[int, int, int]) -> np.ndarray:
    """[N_IN, V] inputs at every voxel centre, x fastest (the robots' label order)."""
    axes = [(np.arange(n) + 0.5) / n * 2 - 1 for n in shape]
    z, y, x = (v.ravel() for v in np.meshgrid(axes[2], axes[1], axes[0], indexing="ij"))
    d = np.sqrt(x * x + y * y + z * z) / math.sqrt(3)
    return np.array([x, y, z, d, np.ones_like(x)])
