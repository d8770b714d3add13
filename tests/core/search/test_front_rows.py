"""`front_rows` reads rows a chunk at a time: the same front, in the same order, whatever the
chunk, with a genome met again counted once."""

from __future__ import annotations

import numpy as np

from softevo.core.search.front import front_rows
from softevo.core.search.vectors import parse_objectives


def rows(seed: int, n: int) -> list[dict]:
    rng = np.random.default_rng(seed)
    genomes = rng.integers(0, 6, size=(37, 2)).astype(float)  # ties between genomes
    found = []
    for i in range(n):
        speed, cost = genomes[i % 37]  # a genome met again measures the same
        found.append(
            {
                "generation": i // 10,
                "index": i % 10,
                "fitness": speed,
                "operator": "crossover",
                "genome_hash": f"g{i % 37}",
                "measures": {"speed": speed, "cost_of_transport": cost},
            }
        )
    return found


def test_every_chunk_gives_the_front_of_all_rows_at_once() -> None:
    specs = parse_objectives(["speed", "-cost_of_transport"])
    for seed in range(5):
        whole = front_rows(specs, rows(seed, 300), chunk=10**6)
        for chunk in (1, 7, 64):
            assert front_rows(specs, iter(rows(seed, 300)), chunk=chunk) == whole
        hashes = [row["genome_hash"] for row in whole]
        assert whole and len(hashes) == len(set(hashes))
