"""The figures of a run with objectives read as they should (issue 48): the objectives and
their units on the axes (cost of transport dimensionless, never "1"), one outlier does not
squash the front, every evaluated robot is a dot, and the hypervolume is drawn against the
simulations run."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from softevo.core.objectives import MEASURES, measure_label
from softevo.core.outputs import figures
from softevo.core.outputs.front_figure import (
    axis_scale,
    front_figure,
    hypervolume_figure,
    objectives_text,
)
from softevo.core.search.vectors import parse_objectives

SPECS = parse_objectives(["speed", "-cost_of_transport"])


def row(index: int, speed: float, cost: float, fitness: float | None = 0.0) -> dict[str, Any]:
    measures = {"speed": speed, "cost_of_transport": cost}
    return {
        "generation": 0,
        "index": index,
        "fitness": fitness,
        "operator": "random",
        "measures": measures,
    }


def population(outlier: float = 8000.0) -> list[dict[str, Any]]:
    rng = np.random.default_rng(0)
    rows = [row(i, float(rng.uniform(0, 0.08)), float(rng.uniform(20, 400))) for i in range(40)]
    rows += [row(40, 0.003, outlier), row(41, 0.05, 300.0, fitness=None)]
    return rows


@pytest.fixture(autouse=True)
def _close_figures() -> Any:
    yield
    figures.pyplot().close("all")


def test_no_measure_is_labelled_with_the_unit_one() -> None:
    assert measure_label("cost_of_transport") == "cost of transport (dimensionless)"
    assert measure_label("speed") == "speed (m/s)"
    assert all("(1)" not in measure_label(name) for name in MEASURES)
    assert objectives_text(SPECS) == "speed (max) against cost of transport (min)"


def test_the_front_figure_names_objectives_and_draws_every_robot() -> None:
    rows = population()
    figure = front_figure(SPECS, rows, f"Pareto front of {objectives_text(SPECS)}")
    (axes,) = figure.axes
    assert axes.get_xlabel() == "speed (m/s), higher is better"
    assert axes.get_ylabel().startswith("cost of transport (dimensionless), lower is better")
    assert "(1" not in axes.get_ylabel() and "speed" in axes.get_title()
    assert "fitness" not in axes.get_title()
    assert axes.get_yscale() == "log"  # the robot at 8000 would flatten the front
    dots = axes.collections[0].get_offsets()
    assert len(dots) == 41  # every robot with measures; the failed one is named, not drawn
    legend = [t.get_text() for t in axes.get_legend().get_texts()]
    assert legend[0] == "evaluated (41 robots; 1 failed, not drawn)"
    assert legend[1].startswith("front (")


def test_an_axis_without_outliers_stays_linear_and_a_signed_one_is_clipped() -> None:
    calm = population(outlier=350.0)
    figure = front_figure(SPECS, calm, "calm")
    assert figure.axes[0].get_yscale() == "linear" and figure.axes[0].get_xscale() == "linear"
    values = np.array([*np.linspace(-0.1, 0.1, 30), -40.0])  # climb rates, one robot falling
    scale = axis_scale(values, np.array([0.05, 0.1]))
    assert scale.kind == "clipped" and scale.limits is not None
    assert values.min() <= -40.0 < scale.limits[0]
    specs = parse_objectives(["forward_speed", "climb_rate"])
    rows = [
        {
            "generation": 0,
            "index": i,
            "fitness": 0.0,
            "operator": "random",
            "measures": {"forward_speed": 0.01 * i * (v > -1), "climb_rate": float(v)},
        }
        for i, v in enumerate(values)
    ]
    (axes,) = front_figure(specs, rows, "signed").axes
    assert axes.get_ylim()[0] > -40.0
    legend = " ".join(t.get_text() for t in axes.get_legend().get_texts())
    assert "1 off the y axis, up to -40" in legend


def test_the_hypervolume_figure_counts_simulations_on_x() -> None:
    curve = [
        {"generation": g, "evaluations": 16 if g == 0 else 8, "hypervolume": 100.0 + g}
        for g in range(4)
    ]
    (axes,) = hypervolume_figure(SPECS, curve, "hypervolume").axes
    (line,) = axes.get_lines()
    assert line.get_xdata().tolist() == [16, 24, 32, 40]
    assert line.get_ydata().tolist() == [100.0, 101.0, 102.0, 103.0]
    assert axes.get_xlabel() == "simulations run (cumulative)"
    assert axes.get_ylabel() == "hypervolume (m/s)"
    assert any("cost of transport 100000" in text.get_text() for text in axes.texts)


def test_the_hypervolume_figure_draws_the_normalised_one_on_a_right_axis() -> None:
    curve = [
        {"generation": 0, "evaluations": 16, "hypervolume": 100.0},  # before the column existed
        {"generation": 1, "evaluations": 8, "hypervolume": 101.0, "normalised_hypervolume": 0.25},
    ]
    axes, right = hypervolume_figure(SPECS, curve, "hypervolume").axes
    (line,) = right.get_lines()
    assert line.get_xdata().tolist() == [16, 24]
    assert np.isnan(line.get_ydata()[0]) and line.get_ydata()[1] == 0.25
    assert right.get_ylim() == (0, 1) and right.get_ylabel() == "normalised hypervolume (0-1)"
    words = " ".join(text.get_text() for text in axes.texts)
    said = "from its reference (0) to its ideal (1):\nspeed 0 to 1, cost of transport 100000 to 0"
    assert said in words
