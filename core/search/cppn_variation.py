"""NEAT variation of CPPN genomes (Stanley & Miikkulainen 2002): perturb weights, add a node
(splitting a connection), add a connection, change an activation, step the robot's a and c;
crossover aligns connections by innovation number. Every draw comes from the generator given.

The strategies call these through `softevo.core.search.variation` when the run's encoding is
`cppn`: a crossover happens with the run's `crossover_probability`; a crossed child is mutated
with its `mutation_probability`, a copy always (a plain copy would be its parent again);
`mutation_genes` NEAT mutations a mutated child (at least one).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from softevo.core.robots.cppn import (
    ACTIVATIONS,
    MUTATIONS,
    N_IN,
    OUTPUT_IDS,
    ROBOT_BOUNDS,
    WEIGHT,
    WEIGHT_RATE,
    WEIGHT_SIGMA,
    Connection,
    CppnEncoding,
    Network,
    innovation,
    split_node,
)
from softevo.core.robots.encodings import EncodingError
from softevo.core.search.state import Individual

if TYPE_CHECKING:
    from softevo.core.search.algorithm import GAConfig

_KINDS = tuple(kind for kind, _ in MUTATIONS)
_CHANCES = np.array([chance for _, chance in MUTATIONS])


def mutate_network(network: Network, rng: np.random.Generator) -> Network:
    """One NEAT mutation, its kind drawn by `MUTATIONS`' chances. A structural mutation with
    nowhere to go (no connection left to add, every split made) perturbs the weights instead."""
    kind = _KINDS[int(rng.choice(len(_KINDS), p=_CHANCES / _CHANCES.sum()))]
    if kind == "node":
        grown = _add_node(network, rng)
        if grown is not None:
            return grown
    elif kind == "connection":
        grown = _add_connection(network, rng)
        if grown is not None:
            return grown
    elif kind == "activation":
        index = int(rng.integers(len(network.nodes)))
        node, _ = network.nodes[index]
        nodes = list(network.nodes)
        nodes[index] = (node, int(rng.integers(len(ACTIVATIONS))))
        return replace(network, nodes=tuple(nodes))
    elif kind == "actuation":
        low, high = ROBOT_BOUNDS.T
        step = rng.normal(0.0, 0.1 * (high - low))
        a, c = np.clip(np.array([network.a, network.c]) + step, low, high).tolist()
        return replace(network, a=a, c=c)
    return _perturb(network, rng)


def _perturb(network: Network, rng: np.random.Generator) -> Network:
    """Each weight stepped with chance WEIGHT_RATE (at least one), clipped to its bounds."""
    n = len(network.connections)
    chosen = rng.random(n) < WEIGHT_RATE
    chosen[int(rng.integers(n))] = True
    steps = rng.normal(0.0, WEIGHT_SIGMA, n) * chosen
    weights = np.clip(
        np.array([link.weight for link in network.connections]) + steps, -WEIGHT, WEIGHT
    )
    links = tuple(
        replace(link, weight=float(w)) for link, w in zip(network.connections, weights, strict=True)
    )
    return replace(network, connections=links)


def _add_node(network: Network, rng: np.random.Generator) -> Network | None:
    """Split an enabled connection s -> t: it is disabled, s -> new (weight 1) and new -> t
    (its weight) added; the new node's id is the pair's, so the same split is one node."""
    ids = {node for node, _ in network.nodes}
    links = [
        ln
        for ln in network.connections
        if ln.enabled and split_node(ln.source, ln.target) not in ids
    ]
    if not links:
        return None
    old = links[int(rng.integers(len(links)))]
    node = split_node(old.source, old.target)
    taken = {link.innovation for link in network.connections}
    new = [
        Connection(innovation(old.source, node), old.source, node, True, 1.0),
        Connection(innovation(node, old.target), node, old.target, True, old.weight),
    ]
    if any(link.innovation in taken for link in new):
        return None
    kept = [replace(ln, enabled=False) if ln is old else ln for ln in network.connections]
    nodes = tuple(
        sorted(
            [*network.nodes, (node, int(rng.integers(len(ACTIVATIONS))))],
            key=lambda item: (item[0] not in OUTPUT_IDS, item[0]),
        )
    )
    connections = tuple(sorted([*kept, *new], key=lambda link: link.innovation))
    return replace(network, nodes=nodes, connections=connections)


def _add_connection(network: Network, rng: np.random.Generator) -> Network | None:
    """A new connection (uniform weight) between two unjoined nodes that makes no cycle."""
    targets = [node for node, _ in network.nodes]
    sources = [*range(N_IN), *(node for node in targets if node not in OUTPUT_IDS)]
    joined = {(link.source, link.target) for link in network.connections}
    pairs = [(s, t) for s in sources for t in targets if s != t and (s, t) not in joined]
    for k in rng.permutation(len(pairs)):
        s, t = pairs[int(k)]
        link = Connection(innovation(s, t), s, t, True, float(rng.uniform(-WEIGHT, WEIGHT)))
        links = tuple(sorted([*network.connections, link], key=lambda ln: ln.innovation))
        grown = replace(network, connections=links)
        try:
            grown.order()
        except EncodingError:
            continue  # it closes a cycle: the next pair
        return grown
    return None


def crossover(base: Network, other: Network, rng: np.random.Generator) -> Network:
    """NEAT crossover: `base`'s structure; a connection both have (same innovation) takes its
    weight and enabled flag from either parent at random, a node both have its activation; the
    disjoint and excess genes are `base`'s. a and c each from either parent."""
    theirs = {link.innovation: link for link in other.connections}
    links = []
    for link in base.connections:
        match = theirs.get(link.innovation)
        links.append(match if match is not None and rng.random() < 0.5 else link)
    their_nodes = dict(other.nodes)
    nodes = tuple(
        (node, their_nodes[node]) if node in their_nodes and rng.random() < 0.5 else (node, act)
        for node, act in base.nodes
    )
    a = other.a if rng.random() < 0.5 else base.a
    c = other.c if rng.random() < 0.5 else base.c
    return Network(nodes, tuple(links), a, c)


def _mutated(network: Network, count: int, rng: np.random.Generator) -> Network:
    for _ in range(max(1, count)):
        network = mutate_network(network, rng)
    return network


def mate(
    config: GAConfig,
    encoding: CppnEncoding,
    pair: tuple[Individual, Individual],
    indices: tuple[int, int],
    rng: np.random.Generator,
) -> list[Individual]:
    """Two children of `pair` (see the module's docstring for the rates)."""
    first, second = (Network.from_genome(item.genome) for item in pair)
    crossed = rng.random() < config.crossover_probability
    if crossed:
        networks = [crossover(first, second, rng), crossover(second, first, rng)]
    else:
        networks = [first, second]
    children = []
    for k, network in enumerate(networks):
        label = "crossover" if crossed else "copy"
        if not crossed or rng.random() < config.mutation_probability:
            label += "+mutation"
            network = _mutated(network, config.mutation_genes, rng)
        parents = tuple(int(i) for i in indices) if crossed else (int(indices[k]),)
        children.append(Individual(network.genome(), label, parents))
    return children


def mutant(
    config: GAConfig,
    encoding: CppnEncoding,
    parent: Individual,
    index: int,
    rng: np.random.Generator,
) -> Individual:
    """A mutated copy of `parent` (`mutation_genes` NEAT mutations, at least one)."""
    network = _mutated(Network.from_genome(parent.genome), config.mutation_genes, rng)
    return Individual(network.genome(), "copy+mutation", (index,))
