"""The front figure of a run with objectives: every evaluated robot as a dot, the front over
them, axes named with units (`softevo run`'s front.png)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from softevo.core.objectives import MEASURES
from softevo.core.outputs.figures import pyplot
from softevo.core.search import pareto
from softevo.core.search.front import Row, front_values
from softevo.core.search.vectors import ObjectiveSpec

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def axis_label(spec: ObjectiveSpec) -> str:
    unit = MEASURES[spec.measure][0]
    goal = "higher is better" if spec.goal == "max" else "lower is better"
    return f"{spec.measure.replace('_', ' ')} ({unit}; {goal})"


def front_figure(specs: Sequence[ObjectiveSpec], rows: Sequence[Row], title: str) -> Figure:
    """Every evaluated robot as a dot in the first two objectives (as measured), the front
    drawn over them as a line of larger points."""
    plt = pyplot()
    figure, axes = plt.subplots(figsize=(5.6, 4.2))
    shown = specs[:2]
    values = front_values(shown, rows) * np.array([spec.sign for spec in shown])
    finite = ~np.isnan(values).any(axis=1)
    mask = np.zeros(len(rows), dtype=bool)
    if len(rows):
        mask = pareto.nondominated_mask(front_values(specs, rows))
    x = values[:, 0]
    y = values[:, 1] if len(shown) > 1 else np.zeros(len(rows))
    axes.scatter(x[finite], y[finite], s=8, color="0.6", label="evaluated")
    order = np.argsort(x[mask], kind="stable")
    axes.plot(x[mask][order], y[mask][order], "o-", color="C3", markersize=5, label="front")
    axes.set_xlabel(axis_label(shown[0]))
    if len(shown) > 1:
        axes.set_ylabel(axis_label(shown[1]))
    axes.set_title(title, fontsize=9)
    axes.legend(fontsize=8)
    figure.tight_layout()
    return figure
