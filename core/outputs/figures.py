"""Publication figures from plain rows (the curve's, the individuals'), the paper's Figure 4(b)-(d).

Nothing here knows where the rows came from (a results folder, the REST API, a sweep), so the
CLI, the API and `softevo reproduce` draw the same figures. matplotlib is imported on first use,
with the Agg backend: no screen needed, and start-up of the commands that never plot stays fast.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, BinaryIO

import numpy as np

from softevo.core.nulls import from_null
from softevo.core.objectives import objective_label

if TYPE_CHECKING:
    from matplotlib.figure import Figure

Row = Mapping[str, Any]


def pyplot() -> Any:
    """matplotlib's pyplot on the Agg backend (no screen), in softevo's figure style."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update(
        {
            "figure.dpi": 110,
            "savefig.dpi": 150,
            "font.size": 9,
            "axes.grid": True,
            "grid.alpha": 0.3,
            "axes.spines.top": False,
            "axes.spines.right": False,
        }
    )
    return plt


SPEED = "speed (m/s)"


def run_title(config: dict[str, Any], run: str = "", fitness: bool = True) -> str:
    """`run 3 (4x4x4, seed 1, speed on flat ground, preset quick)`: a run named with its box,
    seed and task, so a figure says what it shows; `fitness=False` leaves the fitness out (a
    figure of several objectives names them itself)."""
    terrain = config.get("sim", {}).get("terrain", {}).get("kind", "flat")
    shape = config.get("shape")
    objective = config.get("objective") or "speed"
    parts = [
        f"{'x'.join(map(str, shape))}" if shape else "",
        f"seed {config.get('seed')}",
        f"{objective} on {terrain} ground" if fitness else f"{terrain} ground",
        f"preset {config.get('preset') or 'custom'}",
    ]
    inner = ", ".join(p for p in parts if p)
    return f"{run} ({inner})" if run else inner


def fitness_label(config: dict[str, Any]) -> str:
    """The fitness axis of a run's figures: its objective, with units."""
    return objective_label(config.get("objective") or "speed")


def _value(row: Row, key: str) -> float:
    return from_null(row.get(key))


def _generation_axis(axes: Any) -> None:
    from matplotlib.ticker import MaxNLocator

    axes.set_xlabel("generation")
    axes.xaxis.set_major_locator(MaxNLocator(integer=True))


#: What the diversity chart's number is (`softevo.core.search.stats.diversity`), on the figure.
DIVERSITY = "diversity (mean pairwise\nHamming distance)"
DIVERSITY_CAPTION = (
    "diversity: the fraction of discrete genes in which two individuals differ, averaged over "
    "all pairs;\n0 = a population of clones, about 1 - 1/alphabet = uniformly random genomes"
)


def _outside_legend(axes: Any) -> None:
    """The legend right of the data area, where it never covers a point."""
    axes.legend(frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)


def draw_curve(axes: Any, rows: Sequence[Row], title: str, ylabel: str = SPEED) -> None:
    generations = [int(row["generation"]) for row in rows]
    for key, style, colour in (
        ("best", "-", "tab:blue"),
        ("mean", "--", "tab:orange"),
        ("median", ":", "tab:green"),
    ):
        axes.plot(generations, [_value(r, key) for r in rows], style, color=colour, label=key)
    # drawn last, dashed and on top: where it equals `best` it is still seen
    axes.plot(
        generations,
        [_value(r, "best_so_far") for r in rows],
        linestyle=(0, (4, 3)),
        color="black",
        lw=1.6,
        zorder=5,
        label="best so far",
    )
    _generation_axis(axes)
    axes.set_ylabel(ylabel)
    axes.set_title(title)
    _outside_legend(axes)


#: Every individual's generation and fitness (NaN: failed), as two arrays [N]: what the dot plot
#: draws, 16 bytes an individual (the service reads only these two columns of a large run).
Points = tuple[np.ndarray, np.ndarray]


def population_points(individuals: Sequence[Row] | Points) -> Points:
    """`individuals` as Points: rows (a null fitness is NaN), or Points already."""
    if isinstance(individuals, tuple):
        return individuals
    generations = np.array([int(i["generation"]) for i in individuals], dtype=np.int64)
    fitness = np.array([_value(i, "fitness") for i in individuals], dtype=float)
    return generations, fitness


def draw_population(
    axes: Any, individuals: Sequence[Row] | Points, title: str, ylabel: str = SPEED
) -> None:
    generations, fitness = population_points(individuals)
    ok = ~np.isnan(fitness)
    failed = generations[~ok]
    if ok.any():
        axes.scatter(
            generations[ok],
            fitness[ok],
            s=6,
            alpha=0.5,
            color="tab:blue",
            label="individual",
            linewidths=0,
        )
    if len(failed):
        axes.scatter(
            failed,
            np.zeros(len(failed)),
            s=12,
            marker="x",
            color="tab:red",
            label=f"failed ({len(failed)}), at 0",
        )
    _generation_axis(axes)
    axes.set_ylabel(ylabel)
    axes.set_title(title)
    _outside_legend(axes)


def draw_diversity(axes: Any, rows: Sequence[Row], title: str) -> None:
    axes.plot([int(r["generation"]) for r in rows], [_value(r, "diversity") for r in rows])
    _generation_axis(axes)
    axes.set_ylabel(DIVERSITY)
    axes.set_ylim(bottom=0)
    axes.set_title(title)
    axes.annotate(
        DIVERSITY_CAPTION,
        xy=(0, 0),
        xycoords="axes fraction",
        xytext=(0, -34),
        textcoords="offset points",
        va="top",
        fontsize=7,
    )


def _single(draw: Any, data: Sequence[Row], title: str, height: float = 3.4, **how: Any) -> Figure:
    plt = pyplot()
    figure, axes = plt.subplots(figsize=(6.5, height))
    draw(axes, data, title, **how)
    figure.tight_layout()
    return figure


def curve_figure(rows: Sequence[Row], title: str = "learning curve", ylabel: str = SPEED) -> Figure:
    """Figure 4(b): best, mean, median and best so far per generation (fitness: `ylabel`)."""
    return _single(draw_curve, rows, title, ylabel=ylabel)


def population_figure(
    individuals: Sequence[Row] | Points, title: str = "population", ylabel: str = SPEED
) -> Figure:
    """Figure 4(c): every individual's fitness per generation; failed ones as red crosses at 0."""
    return _single(draw_population, individuals, title, ylabel=ylabel)


def diversity_figure(rows: Sequence[Row], title: str = "diversity") -> Figure:
    """Figure 4(d): the population's genetic diversity per generation (defined under it)."""
    return _single(draw_diversity, rows, title, height=3.4)


def panel_figure(
    curve: Sequence[Row], individuals: Sequence[Row], title: str = "", ylabel: str = SPEED
) -> Figure:
    """All three, stacked, for one run: Figure 4(b)-(d) in one file."""
    plt = pyplot()
    figure, axes = plt.subplots(3, 1, figsize=(6.5, 9.5), sharex=True)
    suffix = f": {title}" if title else ""
    draw_curve(axes[0], curve, "learning curve" + suffix, ylabel)
    draw_population(axes[1], individuals, "population" + suffix, ylabel)
    draw_diversity(axes[2], curve, "diversity" + suffix)
    for upper in axes[:2]:
        upper.set_xlabel("")
    figure.tight_layout()
    return figure


#: The file formats a figure is written in, by the file's suffix.
FORMATS = {".png": "png", ".pdf": "pdf", ".svg": "svg"}


def figure_format(path: Path) -> str:
    """The format `path`'s suffix names; ValueError naming the allowed ones otherwise (a
    .pdf that held PNG bytes would open nowhere)."""
    try:
        return FORMATS[path.suffix.lower()]
    except KeyError:
        allowed = ", ".join(FORMATS)
        raise ValueError(
            f"{path}: unknown figure format {path.suffix or '(no suffix)'!r}; use one of {allowed}"
        ) from None


def write(figure: Figure, target: BinaryIO | Path, format: str = "png") -> None:
    """Write the figure and free it (many figures in one process would otherwise pile up)."""
    plt = pyplot()
    figure.savefig(target, format=format)
    plt.close(figure)


def save(figure: Figure, path: Path) -> Path:
    """Write `figure` to `path` in the format of its suffix (.png, .pdf or .svg)."""
    format = figure_format(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write(figure, path, format)
    return path


def run_figures(
    curve: Sequence[Row],
    individuals: Sequence[Row],
    out: Path,
    title: str = "",
    ylabel: str = SPEED,
) -> list[Path]:
    """The three figures of one run into `out`: curve.png, population.png, diversity.png."""
    suffix = f": {title}" if title else ""
    return [
        save(curve_figure(curve, "learning curve" + suffix, ylabel), out / "curve.png"),
        save(population_figure(individuals, "population" + suffix, ylabel), out / "population.png"),
        save(diversity_figure(curve, "diversity" + suffix), out / "diversity.png"),
    ]
