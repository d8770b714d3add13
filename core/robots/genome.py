"""Genomes: the plain data the genetic algorithm breeds, with a stable hash.

A genome is a list of discrete genes (small integers, each with its own alphabet size) and a list
of real genes (each with bounds). What the genes mean is the encoding's business
(`softevo.core.robots.encodings`); the operators in `softevo.core.search.operators` only see
integers and floats.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Genome:
    """One individual's genes. `encoding` names how they become a robot."""

    encoding: str
    discrete: tuple[int, ...]
    real: tuple[float, ...] = ()

    def to_json(self) -> dict[str, Any]:
        return {"encoding": self.encoding, "discrete": list(self.discrete), "real": list(self.real)}

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> Genome:
        return cls(
            encoding=str(data["encoding"]),
            discrete=tuple(int(g) for g in data["discrete"]),
            real=tuple(float(g) for g in data.get("real", ())),
        )

    @cached_property
    def canonical(self) -> str:
        """The genome as canonical JSON (sorted keys, no spaces), computed once: what its hash
        digests, and the text the service stores for it.

        Real genes enter as their shortest round-trip repr, so equal floats hash equally.
        """
        return _CANONICAL(self.to_json())

    @cached_property
    def hash(self) -> str:
        """Stable across processes and machines: sha256 of the canonical JSON, 16 hex digits
        (computed once per genome: the genome is frozen)."""
        return hashlib.sha256(self.canonical.encode()).hexdigest()[:16]


#: The canonical encoder, made once (`json.dumps` with options builds one per call: every bred
#: genome is encoded, for its hash).
_CANONICAL = json.JSONEncoder(separators=(",", ":"), sort_keys=True).encode


def with_genome(fields: dict[str, Any], genome: Genome) -> str:
    """JSON text of `fields` plus `"genome": genome.to_json()`, the genome entering as its
    canonical text (encoded once, for its hash) rather than encoded again."""
    head = json.dumps(fields)[:-1]
    return f'{head}{", " if fields else ""}"genome": {genome.canonical}}}'


def gene_diversity(genomes: list[Genome]) -> float:
    """Mean pairwise normalised Hamming distance of the discrete genes (0 for fewer than 2):
    for every pair, the fraction of positions where they differ. 0 means clones, about
    1 - 1/alphabet uniformly random genomes; real genes do not enter it."""
    if len(genomes) < 2 or not genomes[0].discrete:
        return 0.0
    genes = np.array([g.discrete for g in genomes], dtype=np.int64)
    n, length = genes.shape
    # pairs that differ at a position, from how often each value occurs there: n^2 - sum(c^2)
    # ordered pairs differ, twice the unordered ones; all positions counted in one bincount
    values = genes - genes.min()
    alphabet = int(values.max()) + 1
    counts = np.bincount(
        (values + alphabet * np.arange(length)).ravel(), minlength=alphabet * length
    )
    differing = (length * n * n - int((counts * counts).sum())) // 2
    return differing / (length * n * (n - 1) / 2)
