"""The reproduction's figures: the paper's Figure 4(a)-(d) and the comparisons past it."""

from __future__ import annotations

import math
import statistics
from pathlib import Path
from typing import Any

from softevo.core.outputs import figures
from softevo.reproduce.experiments import Experiments, Group
from softevo.reproduce.plan import CLOCK


def _bars(groups: list[Group], labels: list[str], title: str, path: Path) -> None:
    plt = figures.pyplot()
    figure, axes = plt.subplots(figsize=(6.5, 3.4))
    for x, group in enumerate(groups):
        best = [r["progress"]["best_fitness"] or 0.0 for r in group.runs]
        if best:
            axes.bar(x, statistics.fmean(best), color="tab:blue", alpha=0.6)
            axes.scatter([x] * len(best), best, color="black", s=10, zorder=3)
    axes.set_xticks(range(len(groups)), labels, rotation=30, ha="right")
    axes.set_ylabel("best speed (m/s)")
    axes.set_title(title)
    figure.tight_layout()
    figures.save(figure, path)


def _paired(
    experiments: Experiments,
    shapes: list[tuple[int, int, int]],
    other: tuple[str, str],
    names: tuple[str, str],
    title: str,
    path: Path,
) -> None:
    """Bars per box: the paper-voxel sweep's box, then `other`'s (experiment, variant)."""
    pairs = []
    for shape in shapes:
        pairs += [
            experiments.group("boxes", "paper-voxel", shape),
            experiments.group(*other, shape),
        ]
    labels = [
        f"{'x'.join(map(str, g.shape))} {names[0] if g.experiment == 'boxes' else names[1]}"
        for g in pairs
    ]
    _bars(pairs, labels, title, path)


def write_figures(experiments: Experiments, out: Path) -> dict[str, Any]:
    """Every figure; which run Figure 4(b)-(d) show."""
    shown = _figure4(experiments, out)
    _past_the_paper(experiments, out)
    return shown


def _figure4(experiments: Experiments, out: Path) -> dict[str, Any]:
    """Figure 4(a), and (b)-(d) for the best run of the box with the best mean."""
    boxes = [experiments.group("boxes", "paper-voxel", s) for s in experiments.plan.boxes]
    _bars(
        boxes,
        ["x".join(map(str, g.shape)) for g in boxes],
        "Figure 4(a): best speed on flat ground per bounding box (bars: mean, dots: seeds)",
        out / "fig4a_boxes.png",
    )
    best_box = max(boxes, key=lambda g: g.row()["best_mean"] or -math.inf)
    best_run = max(best_box.runs, key=lambda r: r["progress"]["best_fitness"] or -math.inf)
    title = (
        f"{'x'.join(map(str, best_box.shape))}, seed {best_run['seed']}, speed on flat ground, "
        "paper-voxel"
    )
    curve = experiments.curve(best_run["id"])
    individuals = experiments.individuals(best_run["id"])
    figures.save(
        figures.curve_figure(curve, f"Figure 4(b): learning curve, {title}"),
        out / "fig4b_curve.png",
    )
    figures.save(
        figures.population_figure(individuals, f"Figure 4(c): population, {title}"),
        out / "fig4c_population.png",
    )
    figures.save(
        figures.diversity_figure(curve, f"Figure 4(d): diversity, {title}"),
        out / "fig4d_diversity.png",
    )
    return {
        "figure4_run": best_run["id"],
        "figure4_box": best_box.shape,
        "figure4_seed": best_run["seed"],
    }


def _past_the_paper(experiments: Experiments, out: Path) -> None:
    """Phase 2, the baselines, the encodings, the faster clock and the ablation."""
    plan = experiments.plan
    cube = experiments.group("phase 2", "paper-cube", (1, 1, 1))
    _curves(
        experiments,
        [("paper-cube", cube)],
        "phase 2: the paper cube (1x1x1, speed on flat ground), best so far per seed",
        out / "phase2_cube.png",
        by="generation",
    )
    baselines = [(g.variant, g) for g in experiments.groups if g.experiment == "baselines"]
    _curves(
        experiments,
        baselines,
        f"GA against baselines, {'x'.join(map(str, plan.focus))}, speed on flat ground",
        out / "baselines.png",
        by="evaluations",
    )
    _paired(
        experiments,
        plan.encoding_boxes,
        ("encodings", "spring"),
        ("voxel", "spring"),
        "voxel against spring encoding (bars: mean, dots: seeds)",
        out / "encodings.png",
    )
    _paired(
        experiments,
        plan.boxes,
        CLOCK,
        ("1 rad/s", "2 pi"),
        "the boxes at the paper's actuation (1 rad/s) and at 2 pi rad/s",
        out / "clock.png",
    )
    ablation = [g for g in experiments.groups if g.experiment == "ablation"]
    _bars(
        ablation,
        [g.variant for g in ablation],
        f"ablation, {'x'.join(map(str, plan.focus))}",
        out / "ablation.png",
    )
    _curves(
        experiments,
        [(g.variant, g) for g in ablation],
        f"ablation, {'x'.join(map(str, plan.focus))}, speed on flat ground: best so far",
        out / "ablation_curves.png",
        by="evaluations",
    )


def _curves(
    experiments: Experiments, groups: list[tuple[str, Group]], title: str, path: Path, by: str
) -> None:
    """Best so far of every run of each group, against generation or cumulative simulations."""
    runs = [
        [(run["seed"], experiments.curve(run["id"])) for run in group.runs] for _, group in groups
    ]
    labels = [label for label, _ in groups]
    figures.save(curves_figure(list(zip(labels, runs, strict=True)), title, by), path)


def curves_figure(
    groups: list[tuple[str, list[tuple[int, list[dict[str, Any]]]]]], title: str, by: str
) -> Any:
    """Best so far per run, one legend entry per run (group and seed); one group: a colour per
    seed, several: a colour per group and a line style per seed. `groups`: (label, [(seed,
    curve rows)]); `by`: "generation" or "evaluations" (cumulative simulations)."""
    from matplotlib.ticker import MaxNLocator

    plt = figures.pyplot()
    figure, axes = plt.subplots(figsize=(7.0, 3.4))
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown"]
    styles = ["-", "--", ":", "-."]
    for k, (label, runs) in enumerate(groups):
        for n, (seed, curve) in enumerate(runs):
            if by == "evaluations":
                x, total = [], 0
                for row in curve:
                    total += row["evaluations"]
                    x.append(total)
            else:
                x = [row["generation"] for row in curve]
            axes.plot(
                x,
                [row["best_so_far"] for row in curve],
                color=colours[(n if len(groups) == 1 else k) % len(colours)],
                linestyle="-" if len(groups) == 1 else styles[n % len(styles)],
                alpha=0.8,
                marker="." if len(x) < 20 else None,
                label=f"{label}, seed {seed}",
            )
    axes.set_xlabel("simulations" if by == "evaluations" else "generation")
    axes.xaxis.set_major_locator(MaxNLocator(integer=True))
    axes.set_ylabel("best speed so far (m/s)")
    axes.set_title(title)
    axes.legend(frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    figure.tight_layout()
    return figure
