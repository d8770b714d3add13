"""The MAP-Elites heat map: every cell of an archive coloured by its elite's fitness, empty
cells blank, from the archive's plain JSON (`softevo run`'s archive.json, the API's archive)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from softevo.core.outputs.figures import pyplot
from softevo.core.search.descriptors import CATALOGUE

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def archive_grid(archive: dict[str, Any]) -> np.ndarray:
    """Fitness by cell, NaN where empty: [bins of the first descriptor, of the second] (a
    third descriptor is folded: each of its cells' best)."""
    bins = list(archive["bins"]) + [1] * (2 - len(archive["bins"]))
    grid = np.full(bins[:2], np.nan)
    for elite in archive["elites"]:
        cell = list(elite["cell"]) + [0] * (2 - len(elite["cell"]))
        i, j = cell[0], cell[1]
        if not elite["fitness"] <= grid[i, j]:  # NaN (empty) or lower
            grid[i, j] = elite["fitness"]
    return grid


def archive_figure(archive: dict[str, Any], title: str, label: str) -> Figure:
    """The heat map, descriptor 1 across and descriptor 2 up, with coverage in the title."""
    plt = pyplot()
    names = list(archive["descriptors"])
    grid = archive_grid(archive)
    figure, axes = plt.subplots(figsize=(5.2, 4.2))
    first = CATALOGUE[names[0]]
    extent = [first.low, first.high, 0.0, 1.0]
    if len(names) > 1:
        second = CATALOGUE[names[1]]
        extent[2:] = [second.low, second.high]
        axes.set_ylabel(_wrapped(f"{second.name}: {second.help}"))
    else:
        axes.set_yticks([])
    image = axes.imshow(
        grid.T, origin="lower", extent=extent, aspect="auto", cmap="viridis", interpolation="none"
    )
    axes.grid(False)
    axes.set_xlabel(_wrapped(f"{first.name}: {first.help}", 60))
    filled = int(np.isfinite(grid).sum())
    folded = " (best over " + names[2] + ")" if len(names) > 2 else ""
    axes.set_title(f"{title}\n{filled} of {grid.size} cells filled{folded}", fontsize=9)
    figure.colorbar(image, ax=axes, label=f"elite's {label}")
    figure.tight_layout()
    return figure


def _wrapped(label: str, width: int = 36) -> str:
    """An axis label in lines of at most `width` characters: a descriptor's help is longer than
    the axis, and a y label that long ran into the title."""
    import textwrap

    return "\n".join(textwrap.wrap(label, width))
