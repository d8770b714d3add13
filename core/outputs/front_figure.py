"""The figures of a run with objectives (`softevo run`'s front.png and hypervolume.png): every
evaluated robot as a dot with the front drawn over them, axes named with units, and the
hypervolume of the front so far against the simulations spent on it."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from softevo.core.nulls import from_null
from softevo.core.objectives import measure_label, measure_unit
from softevo.core.outputs.figures import pyplot
from softevo.core.search import pareto
from softevo.core.search.front import Row, front_values
from softevo.core.search.vectors import ObjectiveSpec

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: An axis is squashed when all its dots span more than this many times what the front and the
#: middle half of the dots span together: one robot at 8000 would flatten a front below 400.
SQUASH = 5.0


def axis_label(spec: ObjectiveSpec) -> str:
    goal = "higher is better" if spec.goal == "max" else "lower is better"
    return f"{measure_label(spec.measure)}, {goal}"


def objectives_text(specs: Sequence[ObjectiveSpec]) -> str:
    """`speed (max) against cost of transport (min)`: what a multi-objective figure shows."""
    names = [f"{spec.measure.replace('_', ' ')} ({spec.goal})" for spec in specs]
    return " against ".join(names[:2]) + "".join(f", {name}" for name in names[2:])


@dataclass(frozen=True)
class Scale:
    """How one axis shows its values: linear, log, or linear clipped to `limits`."""

    kind: str = "linear"  # "linear", "log" or "clipped"
    limits: tuple[float, float] | None = None


def axis_scale(values: np.ndarray, front: np.ndarray) -> Scale:
    """Log where outliers would squash the front and every value is positive, the axis clipped
    around the front and the middle half of the dots where some value is not; linear else."""
    if len(values) < 2 or not len(front):
        return Scale()
    q1, q3 = np.percentile(values, [25, 75])
    low, high = min(q1, front.min()), max(q3, front.max())
    reference, span = high - low, values.max() - values.min()
    if reference <= 0 or span <= SQUASH * reference:
        return Scale()
    if values.min() > 0:
        return Scale("log")
    limits = (max(values.min(), low - reference), min(values.max(), high + reference))
    return Scale("clipped", limits)


def _draw_clipped(axes: Any, x: np.ndarray, y: np.ndarray, scales: tuple[Scale, Scale]) -> None:
    """The dots outside a clipped axis, drawn on its edge as arrows pointing out, named in the
    legend with how many they are and how far they go."""
    shown_x, shown_y, outside = x.copy(), y.copy(), np.zeros(len(x), dtype=bool)
    words = []
    for values, shown, scale, name in ((x, shown_x, scales[0], "x"), (y, shown_y, scales[1], "y")):
        if scale.kind != "clipped" or scale.limits is None:
            continue
        lo, hi = scale.limits
        beyond = (values < lo) | (values > hi)
        np.clip(values, lo, hi, out=shown)
        outside |= beyond
        if beyond.any():
            far = values[beyond][np.argmax(np.abs(values[beyond] - (lo + hi) / 2))]
            words.append(f"{beyond.sum()} off the {name} axis, up to {far:.3g}")
    if outside.any():
        axes.scatter(
            shown_x[outside],
            shown_y[outside],
            s=30,
            marker="D",
            facecolors="none",
            edgecolors="C0",
            label="; ".join(words) + " (on its edge)",
            zorder=4,
        )


def _apply(axes: Any, which: str, scale: Scale) -> None:
    if scale.kind == "log":
        getattr(axes, f"set_{which}scale")("log")
    elif scale.kind == "clipped" and scale.limits is not None:
        lo, hi = scale.limits
        pad = 0.04 * (hi - lo)
        getattr(axes, f"set_{which}lim")(lo - pad, hi + pad)


def front_figure(specs: Sequence[ObjectiveSpec], rows: Sequence[Row], title: str) -> Figure:
    """Every evaluated robot as a dot in the first two objectives (as measured), the front
    drawn over them as a line of larger points; an axis an outlier would squash is drawn in log
    or clipped with the outliers marked (`axis_scale`)."""
    plt = pyplot()
    figure, axes = plt.subplots(figsize=(6.4, 4.6))
    shown = specs[:2]
    values = front_values(shown, rows) * np.array([spec.sign for spec in shown])
    finite = ~np.isnan(values).any(axis=1)
    mask = np.zeros(len(rows), dtype=bool)
    if len(rows):
        mask = pareto.nondominated_mask(front_values(specs, rows))
    x = values[:, 0]
    y = values[:, 1] if len(shown) > 1 else np.zeros(len(rows))
    scales = (axis_scale(x[finite], x[mask]), Scale())
    if len(shown) > 1:
        scales = (scales[0], axis_scale(y[finite], y[mask]))
    inside = finite & _within(x, scales[0]) & _within(y, scales[1])
    failed = sum(row.get("fitness") is None for row in rows)
    label = f"evaluated ({int(finite.sum())} robots" + (
        f"; {failed} failed, not drawn)" if failed else ")"
    )
    axes.scatter(x[inside], y[inside], s=9, color="0.6", label=label, zorder=2)
    _draw_clipped(axes, x[finite], y[finite], scales)
    order = np.argsort(x[mask], kind="stable")
    axes.plot(
        x[mask][order],
        y[mask][order],
        "o-",
        color="C3",
        markersize=5,
        zorder=5,
        label=f"front ({int(mask.sum())} robots)",
    )
    _apply(axes, "x", scales[0])
    _apply(axes, "y", scales[1])
    axes.set_xlabel(axis_label(shown[0]) + (" (log scale)" if scales[0].kind == "log" else ""))
    if len(shown) > 1:
        axes.set_ylabel(axis_label(shown[1]) + (" (log scale)" if scales[1].kind == "log" else ""))
    axes.set_title(title, fontsize=9)
    axes.legend(fontsize=8, loc="best")
    figure.tight_layout()
    return figure


def _within(values: np.ndarray, scale: Scale) -> np.ndarray:
    if scale.kind != "clipped" or scale.limits is None:
        return np.ones(len(values), dtype=bool)
    return (values >= scale.limits[0]) & (values <= scale.limits[1])


def hypervolume_unit(specs: Sequence[ObjectiveSpec]) -> str:
    """The unit of a hypervolume: the product of its objectives' units, pure numbers left out."""
    units = [measure_unit(spec.measure) for spec in specs]
    kept = [unit for unit in units if unit not in ("dimensionless", "count", "0 or 1")]
    return " \N{MULTIPLICATION SIGN} ".join(kept) if kept else "dimensionless"


def hypervolume_figure(specs: Sequence[ObjectiveSpec], curve: Sequence[Row], title: str) -> Figure:
    """The hypervolume of the front so far after each generation against the simulations run
    until then (the curve's `evaluations`, summed): what a fair comparison of algorithms with
    different generation sizes reads; and, on a right axis, its normalised hypervolume (0-1)
    where the curve has it."""
    plt = pyplot()
    figure, axes = plt.subplots(figsize=(6.4, 3.8))
    spent = np.cumsum([int(row.get("evaluations") or 0) for row in curve])
    volume = np.array([from_null(row.get("hypervolume")) for row in curve], dtype=float)
    axes.plot(spent, volume, "o-", drawstyle="steps-post", color="C0", markersize=3)
    if len(curve):
        last = int(curve[-1]["generation"])
        axes.annotate(
            f"generation {last}",
            (spent[-1], volume[-1]),
            xytext=(-4, -12),
            textcoords="offset points",
            ha="right",
            fontsize=8,
        )
    reference = ", ".join(f"{spec.measure.replace('_', ' ')} {spec.reference:g}" for spec in specs)
    axes.set_xlabel("simulations run (cumulative)")
    axes.set_ylabel(f"hypervolume ({hypervolume_unit(specs)})")
    axes.set_ylim(bottom=0)
    axes.set_xlim(left=0)
    axes.set_title(title, fontsize=9)
    scaled = _normalised(axes, spent, curve, specs)
    axes.annotate(
        f"the volume the front dominates, bounded by the reference point: {reference}{scaled}",
        xy=(0, 0),
        xycoords="axes fraction",
        xytext=(0, -30),
        textcoords="offset points",
        va="top",
        fontsize=7,
    )
    figure.tight_layout()
    return figure


def _normalised(
    axes: Any, spent: np.ndarray, curve: Sequence[Row], specs: Sequence[ObjectiveSpec]
) -> str:
    """The curve's normalised hypervolume, dashed on a right axis from 0 to 1 (nothing for a
    curve without it), and the words that say what it is ("" when not drawn)."""
    scaled = np.array([from_null(row.get("normalised_hypervolume")) for row in curve], dtype=float)
    if not np.isfinite(scaled).any():
        return ""
    right = axes.twinx()
    right.plot(spent, scaled, "--", drawstyle="steps-post", color="C3", linewidth=1.2)
    right.set_ylim(0, 1)
    right.set_ylabel("normalised hypervolume (0-1)", color="C3")
    bounds = ", ".join(
        f"{spec.measure.replace('_', ' ')} {spec.reference:g} to {spec.ideal:g}" for spec in specs
    )
    return (
        f";\ndashed: normalised, each objective from its reference (0) to its ideal (1):\n{bounds}"
    )
