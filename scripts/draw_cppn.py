"""Draw docs/img/cppn-bodies.png: bodies the `cppn` encoding grows in an 8x8x8 box (no
simulation). Top row: random genomes of seed 1, as a run's first generation draws them; bottom
row: the first of them after 1, 2, 4 and 8 NEAT mutations. `python scripts/draw_cppn.py`."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from softevo.core.outputs import figures
from softevo.core.outputs.picture import thumbnail_png
from softevo.core.robots.cppn import Network
from softevo.core.robots.cppn_encoding import CppnEncoding
from softevo.core.robots.cppn_variation import mutate_network
from softevo.core.robots.settings import SimSettings

SHAPE = (8, 8, 8)


def bodies() -> list[tuple[str, object]]:
    """(title, robot) pairs of the two rows."""
    encoding, rng, sim = CppnEncoding(SHAPE), np.random.default_rng(1), SimSettings()
    genomes = []
    while len(genomes) < 4:
        genome = encoding.random(rng)
        if any(label != "empty" for label in encoding.to_robot(genome, sim).voxels):
            genomes.append(genome)
    drawn = [(f"random {k + 1}", encoding.to_robot(g, sim)) for k, g in enumerate(genomes)]
    network, done = Network.from_genome(genomes[0]), 0
    for count in (1, 2, 4, 8):
        while done < count:
            network, done = mutate_network(network, rng), done + 1
        drawn.append((f"random 1, {count} mutations", encoding.to_robot(network.genome(), sim)))
    return drawn


def main() -> None:
    plt = figures.pyplot()
    figure, axes = plt.subplots(2, 4, figsize=(8.0, 4.2))
    for ax, (title, robot) in zip(axes.ravel(), bodies(), strict=True):
        ax.imshow(plt.imread(io.BytesIO(thumbnail_png(robot, (280, 210)))))  # type: ignore[arg-type]
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    figure.tight_layout()
    figures.save(figure, Path(__file__).resolve().parents[1] / "docs" / "img" / "cppn-bodies.png")


if __name__ == "__main__":
    main()
