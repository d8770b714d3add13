"""The figures say what they show and hide nothing (issue 19): drawn from real rows, then the
matplotlib artists read back."""

from __future__ import annotations

from typing import Any

import pytest

from softevo.core.outputs import figures
from softevo.reproduce.figures import curves_figure

CONFIG = {"shape": [3, 2, 2], "seed": 4, "preset": "quick", "objective": "speed", "sim": {}}


def curve(n: int = 6, best: float = 0.1) -> list[dict[str, Any]]:
    rows = []
    for g in range(n):
        rows.append(
            {
                "generation": g,
                "best": best + 0.01 * g,
                "mean": 0.05,
                "median": 0.04,
                "best_so_far": best + 0.01 * g,
                "diversity": 0.5 - 0.05 * g,
                "evaluations": 5,
            }
        )
    return rows


def individuals() -> list[dict[str, Any]]:
    rows = [{"generation": g, "fitness": 0.01 * i} for g in range(6) for i in range(8)]
    return [*rows, {"generation": 2, "fitness": None}]


@pytest.fixture(autouse=True)
def _close_figures() -> Any:
    yield
    figures.pyplot().close("all")


def _inside(axes: Any, legend: Any) -> bool:
    figure = axes.figure
    figure.canvas.draw()
    box, data = legend.get_window_extent(), axes.get_window_extent()
    return box.overlaps(data)


def test_best_so_far_is_drawn_on_top_dashed_in_its_own_colour() -> None:
    figure = figures.curve_figure(curve(), "learning curve", "speed (m/s)")
    (axes,) = figure.axes
    lines = {line.get_label(): line for line in axes.get_lines()}
    best, so_far = lines["best"], lines["best so far"]
    assert so_far.get_ydata().tolist() == best.get_ydata().tolist()  # the same values...
    assert so_far.get_zorder() > best.get_zorder()  # ...drawn over it
    assert so_far.get_linestyle() not in ("-", "solid")
    assert so_far.get_color() != best.get_color()
    assert not _inside(axes, axes.get_legend())


def test_population_legend_stays_out_of_the_data() -> None:
    figure = figures.population_figure(individuals(), "population")
    (axes,) = figure.axes
    texts = [t.get_text() for t in axes.get_legend().get_texts()]
    assert texts == ["individual", "failed (1), at 0"]
    assert not _inside(axes, axes.get_legend())


def test_diversity_is_defined_on_its_figure_and_titles_name_the_task() -> None:
    title = figures.run_title(CONFIG)
    assert title == "3x2x2, seed 4, speed on flat ground, preset quick"
    figure = figures.diversity_figure(curve(), f"diversity: {title}")
    (axes,) = figure.axes
    words = " ".join(t.get_text() for t in axes.texts) + axes.get_ylabel()
    assert "Hamming" in words and "differ" in words and "clones" in words
    for tick in axes.get_xticks():
        assert float(tick).is_integer()


def test_run_curves_give_each_seed_a_colour_an_entry_and_whole_generations() -> None:
    figure = curves_figure(
        [("paper-cube", [(1, curve(3, 0.1)), (2, curve(3, 0.2))])], "phase 2", "generation"
    )
    (axes,) = figure.axes
    lines = axes.get_lines()
    assert [line.get_label() for line in lines] == ["paper-cube, seed 1", "paper-cube, seed 2"]
    assert lines[0].get_color() != lines[1].get_color()
    assert [t.get_text() for t in axes.get_legend().get_texts()] == [
        "paper-cube, seed 1",
        "paper-cube, seed 2",
    ]
    figure.canvas.draw()
    assert all(float(t).is_integer() for t in axes.get_xticks())
    several = curves_figure(
        [("ga", [(1, curve()), (2, curve())]), ("random", [(1, curve())])], "b", "evaluations"
    )
    styles = [(line.get_color(), line.get_linestyle()) for line in several.axes[0].get_lines()]
    assert len(set(styles)) == 3  # every run tells apart from the others
