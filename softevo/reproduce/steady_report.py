"""The tables and figure of `softevo reproduce --steady` (`steady.Results`): steady.csv,
timing.csv, steady.md and steady.png in --out."""

from __future__ import annotations

import csv
import statistics
from pathlib import Path
from typing import Any

from softevo.core.outputs import figures
from softevo.reproduce.experiments import wall_seconds
from softevo.reproduce.steady import (
    BESIDE,
    GA,
    LONG,
    METHODS,
    RUNNING,
    STEADY,
    Results,
    box,
    prefix_holds,
    repeated,
    simulations,
)
from softevo.reproduce.tables import fmt

COLOURS = {GA: "tab:blue", STEADY: "tab:orange", LONG: "tab:orange"}
STYLES = ("-", "--", ":", "-.")


def steady_rows(results: Results) -> list[dict[str, Any]]:
    """One row per box and method: best speed, simulations, births and wall time over seeds."""
    rows = []
    for shape in results.plan["shapes"]:
        for method in METHODS:
            keys = [(box(shape), method, seed) for seed in results.plan["seeds"]]
            runs = [results.runs[k] for k in keys]
            curves = [results.curves[k] for k in keys]
            best = [c[-1]["best_so_far"] for c in curves]
            sims = [simulations(c) for c in curves]
            walls = [wall_seconds(r) for r in runs]
            beside = [wall_seconds(results.runs[(k[0], BESIDE[method], k[2])]) for k in keys]
            population = runs[0]["config"]["population"]
            rows.append(
                {
                    "box": box(shape),
                    "method": method,
                    "best_by_seed": " ".join(f"{b:.4f}" for b in best),
                    "best_mean": statistics.fmean(best),
                    "best_std": statistics.pstdev(best),
                    "simulations_by_seed": " ".join(map(str, sims)),
                    "simulations_mean": statistics.fmean(sims),
                    "births_by_seed": " ".join(str(len(c) * population) for c in curves),
                    "wall_by_seed": " ".join(f"{w:.1f}" for w in walls),
                    "wall_mean": statistics.fmean(walls),
                    "wall_std": statistics.pstdev(walls),
                    "ga_beside_by_seed": " ".join(f"{w:.1f}" for w in beside),
                    "ga_beside_mean": statistics.fmean(beside),
                    "wall_ratio": sum(walls) / sum(beside),
                    "seconds_per_simulation": sum(walls) / sum(sims),
                }
            )
    return rows


def write_steady(results: Results, out: Path, command: str, wall: float) -> list[Path]:
    """steady.csv, timing.csv, steady.md and steady.png."""
    rows = steady_rows(results)
    _csv(out / "steady.csv", rows)
    _csv(out / "timing.csv", [results.timing])
    lines = [
        *_table(results, rows),
        *_timing(results.timing),
        f"Command: `{command}`; {wall:.0f} s.",
        "",
    ]
    (out / "steady.md").write_text("\n".join(lines))
    return [
        out / "steady.csv",
        out / "timing.csv",
        out / "steady.md",
        _figure(results, rows, out / "steady.png"),
    ]


def _csv(path: Path, rows: list[dict[str, Any]]) -> None:
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, list(rows[0]), lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)


def _table(results: Results, rows: list[dict[str, Any]]) -> list[str]:
    keys = [(box(s), seed) for s in results.plan["shapes"] for seed in results.plan["seeds"]]
    held = sum(prefix_holds(results, *key) for key in keys)
    again = sum(repeated(results, *key) for key in keys)
    ga = [r for r in rows if r["method"] == GA]
    noise = statistics.fmean(abs(r["wall_ratio"] - 1) for r in ga)
    lines = [
        "# Steady-state against the paper's GA, on the same simulations",
        "",
        f"Every run alone on the private service ({RUNNING} at a time, the pool on every core). "
        f"'{STEADY}': the rows of steady-state whose simulations stay within the GA's on that "
        f"box and seed; its curve is the first rows of '{LONG}' (as many births as the GA) in "
        f"{held} of {len(keys)} runs. Wall time: from the run's start to its end, as the API "
        "reports them. Each steady-state run was submitted right after a GA run of its box and "
        f"seed, the one in 'GA beside it' (for '{STEADY}' the GA run again, which gave its first "
        f"curve in {again} of {len(keys)} runs); the ratio is their total wall times'. In the GA "
        f"rows, 'GA beside it' is that second GA run, and the ratio (off 1 by {noise:.0%} on "
        "average) says how much the machine's load moved a run's wall time.",
        "",
        "| box | method | best speed, m/s (mean ± std) | by seed | simulations | births | wall "
        "time, s (mean ± std) | by seed | GA beside it, s | ratio | s per simulation |",
        "| --- | --- | ---: | --- | ---: | --- | ---: | --- | ---: | ---: | ---: |",
    ]
    for r in rows:
        lines.append(
            f"| {r['box']} | {r['method']} | {fmt(r['best_mean'])} ± {fmt(r['best_std'])} | "
            f"{r['best_by_seed']} | {r['simulations_mean']:.0f} | {r['births_by_seed']} | "
            f"{r['wall_mean']:.1f} ± {r['wall_std']:.1f} | {r['wall_by_seed']} | "
            f"{r['ga_beside_mean']:.1f} | {r['wall_ratio']:.2f} | "
            f"{r['seconds_per_simulation']:.3f} |"
        )
    return [*lines, ""]


def _timing(timing: dict[str, Any]) -> list[str]:
    return [
        "## Robots that take time in proportion to their size",
        "",
        f"The '{STEADY}' run of {timing['box']}, seed {timing['seed']} ({timing['rows']} rows), "
        f"in process (`Evolution` on {timing['workers']} worker processes), twice: as it is, and "
        f"with every batch held {timing['per_voxel'] * 1000:g} ms per voxel of its robots "
        f"before its real fitness returns, {timing['slots']} batches at once. "
        f"{timing['overtaken']} of {timing['batches']} batches landed after a batch of later "
        f"births; the holds added {timing['held_seconds']:.1f} s of waiting.",
        "",
        "| curve identical | final state identical | curve identical to the service's | best "
        "speed, m/s | wall time as it is, s | wall time size-timed, s |",
        "| --- | --- | --- | ---: | ---: | ---: |",
        f"| {timing['curve_equal']} | {timing['state_equal']} | {timing['service_equal']} | "
        f"{fmt(timing['best'])} | {timing['wall_instant']:.1f} | {timing['wall_timed']:.1f} |",
        "",
    ]


def _figure(results: Results, rows: list[dict[str, Any]], path: Path) -> Path:
    """Per box: best speed so far against simulations (GA; steady-state for the GA's births,
    a dot where its matched run ends), and the wall times."""
    plt = figures.pyplot()
    shapes = results.plan["shapes"]
    figure, axes = plt.subplots(
        2, len(shapes), figsize=(4.0 * len(shapes) + 1.6, 6.2), squeeze=False, height_ratios=(2, 1)
    )
    for column, shape in enumerate(shapes):
        name, ax = box(shape), axes[0][column]
        for n, seed in enumerate(results.plan["seeds"]):
            for method in (GA, LONG):
                curve = results.curves[(name, method, seed)]
                x = [simulations(curve, i + 1) for i in range(len(curve))]
                label = f"{'GA' if method == GA else 'steady-state'}, seed {seed}"
                ax.plot(
                    x,
                    [r["best_so_far"] for r in curve],
                    color=COLOURS[method],
                    ls=STYLES[n % len(STYLES)],
                    lw=1.1,
                    label=label,
                )
            matched = results.curves[(name, STEADY, seed)]
            ax.plot(
                simulations(matched), matched[-1]["best_so_far"], "o", ms=4, color=COLOURS[STEADY]
            )
            ax.axvline(results.budgets[(name, seed)], color="0.6", lw=0.5, ls=STYLES[n % 4])
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("simulations")
        _walls(axes[1][column], [r for r in rows if r["box"] == name])
    axes[0][0].set_ylabel("best speed so far (m/s)")
    axes[1][0].set_ylabel("wall time, s (alone;\nin pairs, as taken)")
    axes[0][-1].legend(fontsize=7, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    figure.suptitle(
        "steady-state against the paper's GA (grey: the GA's simulations; dot: "
        "steady-state on them)",
        fontsize=9,
    )
    figure.tight_layout()
    return figures.save(figure, path)


def _walls(ax: Any, rows: list[dict[str, Any]]) -> None:
    """Wall times in the pairs they were taken in: each steady-state run beside the GA run
    submitted just before it (bars: the mean; dots: the seeds)."""
    by = {row["method"]: row for row in rows}
    bars = [
        ("GA,\nround 1", by[GA]["wall_by_seed"], COLOURS[GA]),
        ("steady-state,\nGA's births", by[LONG]["wall_by_seed"], COLOURS[LONG]),
        ("GA,\nround 2", by[GA]["ga_beside_by_seed"], COLOURS[GA]),
        ("steady-state,\nGA's sims", by[STEADY]["wall_by_seed"], COLOURS[STEADY]),
    ]
    for x, (_, text, colour) in enumerate(bars):
        walls = [float(w) for w in text.split()]
        ax.bar(x, statistics.fmean(walls), color=colour, alpha=0.7)
        ax.scatter([x] * len(walls), walls, color="black", s=8, zorder=3)
    ax.set_xticks(range(len(bars)), [label for label, _, _ in bars], fontsize=7)
