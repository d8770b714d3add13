"""Which MAP-Elites variation explores? `python bench/map_elites_variation.py [VARIANT ...]`.

Runs MAP-Elites on 4x4x4 at paper-voxel settings (25 robots a generation), archive voxels x
actuated (8 x 8), 80 generations (at most 2000 simulations), seeds 1-3, one variant's runs
after another on one process, and prints each variant's mean coverage, QD-score and best speed
(and each seed's). `today` is the map-elites preset before issue 38 (the paper's crossover and
mutation of elites, plus immigrants), reached through the default options; the others set
MAP-Elites' `options` (docs/evolution.md). Each finished run is kept as JSON in --out, so a
variant already measured is read back, not run again. A 2000-simulation run takes about 3
minutes of one core. `--random-cells` only counts the cells random genomes fall in.
"""

from __future__ import annotations

import argparse
import json
import statistics
from collections import Counter
from pathlib import Path
from typing import Any

from softevo import library

BASE: dict[str, Any] = {
    "preset": "paper-voxel",
    "algorithm": "map-elites",
    "descriptors": ["voxels", "actuated"],
    "bins": [8, 8],
    "shape": [4, 4, 4],
    "generations": 80,
}
MUTATION = {"variation": "mutation"}
VARIANTS: dict[str, dict[str, Any]] = {
    "today": {},
    "today-g100": {"generations": 100},  # as many simulations as the others (its cache saves)
    "gaussian": {"options": {**MUTATION, "label_rate": 0.05}},
    "iso-line": {"options": {**MUTATION, "label_rate": 0.05, "real": "iso-line"}},
    "iso-line-0imm": {
        "immigrants": 0.0,
        "options": {**MUTATION, "label_rate": 0.05, "real": "iso-line"},
    },
    "iso-line-r10": {
        "immigrants": 0.0,
        "options": {**MUTATION, "label_rate": 0.1, "real": "iso-line"},
    },
    "iso-line-r02": {
        "immigrants": 0.0,
        "options": {**MUTATION, "label_rate": 0.02, "real": "iso-line"},
    },
    "today-spread": {"options": {"random": "spread"}},
    "explore": {
        "options": {**MUTATION, "label_rate": 0.05, "real": "iso-line", "random": "spread"},
    },
    "explore-r10": {
        "options": {**MUTATION, "label_rate": 0.1, "real": "iso-line", "random": "spread"},
    },
    "preset": {"preset": "map-elites", "generations": 80},  # today-spread's config
}
SEEDS = (1, 2, 3)


def measure(name: str, seed: int, out: Path) -> dict[str, Any]:
    """One run's coverage, QD-score, best speed and simulations (read back if kept)."""
    path = out / f"{name}-{seed}.json"
    if path.exists():
        return json.loads(path.read_text())
    overrides = VARIANTS[name]
    config = {**BASE, **overrides, "seed": seed}
    if overrides.get("preset") == "map-elites":  # the preset's own map and options
        config = {key: config[key] for key in ("preset", "generations", "seed")}
    result = library.evolve(config, workers=1)
    archive = result.archive or {"elites": []}
    row = {
        "variant": name,
        "seed": seed,
        "coverage": result.curve[-1]["coverage"],
        "qd_score": result.curve[-1]["qd_score"],
        "best": result.best_fitness,
        "simulations": result.evaluations,
        "cells": len(archive["elites"]),
        "wall_s": result.wall_seconds,
        "config": result.config,
    }
    path.write_text(json.dumps(row, indent=1))
    return row


def random_cells(draws: int = 2000) -> None:
    """Where random genomes land on the map, with no simulation: the cells that `draws` uniform
    and `draws` spread 4x4x4 genomes fall in (why generation 0 and the immigrants matter)."""
    import numpy as np

    from softevo.core.robots.encodings import VoxelEncoding
    from softevo.core.search.archive import Archive
    from softevo.core.search.descriptors import describe
    from softevo.core.search.map_elites import spread_random

    encoding, archive = VoxelEncoding((4, 4, 4)), Archive(("voxels", "actuated"), (8, 8))
    for name in ("uniform", "spread"):
        rng, cells = np.random.default_rng(0), Counter[tuple[int, ...]]()
        for _ in range(draws):
            genome = encoding.random(rng) if name == "uniform" else spread_random(encoding, rng)
            values = describe(archive.names, genome.discrete, encoding.shape)
            if values:
                cells[archive.cell(values)] += 1
        top = sum(count for _, count in cells.most_common(4)) / draws
        print(f"{draws} {name} random genomes: {len(cells)} of 64 cells, {top:.0%} in the top 4")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("variants", nargs="*", default=list(VARIANTS), help="default: all")
    parser.add_argument("--out", type=Path, default=Path("map_elites_variation"))
    parser.add_argument("--seeds", default="1,2,3", help="comma-separated (default 1,2,3)")
    parser.add_argument(
        "--random-cells", action="store_true", help="only count the cells random genomes hit"
    )
    args = parser.parse_args()
    if args.random_cells:
        random_cells()
        return
    unknown = [name for name in args.variants if name not in VARIANTS]
    if unknown:
        parser.error(f"unknown variants {unknown} (known: {', '.join(VARIANTS)})")
    args.out.mkdir(parents=True, exist_ok=True)
    seeds = [int(seed) for seed in args.seeds.split(",")]
    print("| variant | coverage | QD-score | best speed, m/s | simulations | by seed |")
    print("| --- | ---: | ---: | ---: | ---: | --- |")
    for name in args.variants:
        print(table_row(name, [measure(name, seed, args.out) for seed in seeds]), flush=True)


def table_row(name: str, rows: list[dict[str, Any]]) -> str:
    """A variant's means over seeds, and each seed's coverage / QD-score / best speed."""

    def mean(key: str) -> float:
        return statistics.fmean(row[key] for row in rows)

    by_seed = ", ".join(f"{r['coverage']:.3f}/{r['qd_score']:.2f}/{r['best']:.4f}" for r in rows)
    return (
        f"| {name} | {mean('coverage'):.3f} | {mean('qd_score'):.3f} | {mean('best'):.4f} "
        f"| {mean('simulations'):.0f} | {by_seed} |"
    )


if __name__ == "__main__":
    main()
