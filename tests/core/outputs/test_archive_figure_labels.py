"""archive.png's axis labels stay clear of its title whatever the descriptors (issue 39: the
y label, a descriptor's whole help on one line, ran into the title)."""

from __future__ import annotations

from softevo.core.outputs.archive_figures import archive_figure
from softevo.core.search.descriptors import CATALOGUE


def test_the_longest_y_label_stays_clear_of_the_title() -> None:
    longest = max(CATALOGUE.values(), key=lambda d: len(f"{d.name}: {d.help}"))
    first = next(name for name in CATALOGUE if name != longest.name)
    archive = {"descriptors": [first, longest.name], "bins": [8, 8], "elites": []}
    title = "MAP-Elites archive: 3x3x3, seed 0, speed on flat ground, preset quick"
    figure = archive_figure(archive, title, "speed (m/s)")
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()  # type: ignore[attr-defined]
    axes = figure.axes[0]
    label = axes.yaxis.label.get_window_extent(renderer)
    heading = axes.title.get_window_extent(renderer)
    assert not label.overlaps(heading)
    assert label.y1 <= axes.get_window_extent(renderer).y1 + 1  # within the plot's height
