"""A run's Pareto front: the non-dominated set of every individual it evaluated, and its figure.

Individuals come as plain rows (`generation`, `index`, `fitness`, `operator`, `measures`), as
population.csv, the store and `GET /runs/{id}/individuals` give them. A `survivor` row is the
same genome again (its record comes from the cache), so it is counted once, where it first
appeared. A failed row (no fitness, or an objective not measured) is on no front.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from softevo.core.figures import pyplot
from softevo.core.ga import pareto
from softevo.core.ga.vectors import ObjectiveSpec, objective_values
from softevo.core.objectives import MEASURES

if TYPE_CHECKING:
    from matplotlib.figure import Figure

Row = Mapping[str, Any]


def front_values(specs: Sequence[ObjectiveSpec], rows: Sequence[Row]) -> np.ndarray:
    """[N, M] maximised objective values of the rows (NaN: failed, or a survivor's repeat)."""
    fitness = np.array(
        [np.nan if row["fitness"] is None else row["fitness"] for row in rows], dtype=np.float64
    )
    fitness[[row.get("operator") == "survivor" for row in rows]] = np.nan
    records = [row.get("measures") or {} for row in rows]
    return objective_values(specs, records, fitness).reshape(len(rows), max(1, len(specs)))


def front_rows(specs: Sequence[ObjectiveSpec], rows: Sequence[Row]) -> list[Row]:
    """The rows on the front, in their order: no other row dominates them."""
    if not rows:
        return []
    mask = pareto.nondominated_mask(front_values(specs, rows))
    return [row for row, kept in zip(rows, mask, strict=True) if kept]


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
