"""The tables and figures of `softevo reproduce --objectives` (`objectives.Results`): tradeoff.csv,
afpo.csv, objectives.md, fronts.png, hypervolume.png and afpo.png in --out."""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

from softevo.core.outputs import figures
from softevo.reproduce.objectives import (
    AGE_METHODS,
    COLLAPSE,
    COT_REFERENCE,
    COT_SCALE,
    SPEED_SCALE,
    SPEED_WEIGHTS,
    TRADE_METHODS,
    Results,
    age_rows,
    simulations_at,
    trade_rows,
)
from softevo.reproduce.tables import fmt

COLOURS = dict(
    zip(TRADE_METHODS, ("tab:red", "tab:blue", "tab:purple", "tab:green", "0.5"), strict=True)
)
AGE_COLOURS = {"GA": "tab:blue", "AFPO": "tab:orange"}
STYLES = ("-", "--", ":", "-.")


def write_objectives(results: Results, out: Path, command: str, wall: float) -> list[Path]:
    """Both tables as CSV and Markdown, and the three figures."""
    trade, age = trade_rows(results), age_rows(results)
    for name, rows in (("tradeoff.csv", trade), ("afpo.csv", age)):
        with (out / name).open("w", newline="") as handle:
            writer = csv.DictWriter(handle, list(rows[0]), lineterminator="\n")
            writer.writeheader()
            writer.writerows(rows)
    lines = [
        *_trade_table(results, trade),
        *_age_table(age),
        f"Command: `{command}`; {wall:.0f} s.",
        "",
    ]
    (out / "objectives.md").write_text("\n".join(lines))
    return [
        out / "tradeoff.csv",
        out / "afpo.csv",
        out / "objectives.md",
        _fronts(results, out / "fronts.png"),
        _volumes(results, out / "hypervolume.png"),
        _age(results, out / "afpo.png"),
    ]


def _trade_table(results: Results, rows: list[dict[str, Any]]) -> list[str]:
    budgets = ", ".join(f"seed {s}: {b:.0f}" for s, b in results.budgets.items())
    weights = ", ".join(f"{w:g}" for w in SPEED_WEIGHTS)
    lines = [
        "# Several objectives: NSGA-II, a weighted-sum GA and random search; AFPO against the GA",
        "",
        f"## Speed against cost of transport ({'x'.join(map(str, results.plan['front_shape']))})",
        "",
        f"Every run read at its last generation within the seed's budget ({budgets} "
        "simulations: the mean of the three weighted GAs). Hypervolume against the reference "
        f"point (speed 0 m/s, cost of transport {COT_REFERENCE:g}), stored with every run; the "
        "wide column against the default reference (0, 100000). Weighted GA: selection on "
        f"w speed / {SPEED_SCALE:g} - (1 - w) cost of transport / {COT_SCALE:g}, w = {weights}.",
        "",
        "| method | hypervolume (mean ± std) | by seed | wide hypervolume | front size | best "
        "speed (m/s) | lowest cost of transport on the front | simulations | generations read |",
        "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | --- |",
    ]
    for r in rows:
        lines.append(
            f"| {r['method']} | {fmt(r['hypervolume_mean'], 2)} ± {fmt(r['hypervolume_std'], 2)} "
            f"| {r['hypervolume_by_seed']} | {fmt(r['hypervolume_default_mean'], 0)} | "
            f"{r['front_size_mean']:.1f} | {fmt(r['best_speed_mean'])} | "
            f"{fmt(r['lowest_cot_mean'], 0)} | {r['simulations_mean']:.0f} | "
            f"{r['generations_read']} |"
        )
    return [*lines, ""]


def _age_table(rows: list[dict[str, Any]]) -> list[str]:
    lines = [
        "## AFPO against the paper's GA, speed alone, the same simulations",
        "",
        f"Collapse: the first generation whose diversity is below {COLLAPSE:g} ('-': never).",
        "",
        "| box | method | best speed, m/s (mean ± std) | by seed | simulations | generations | "
        "collapse (by seed) | lowest diversity | final diversity |",
        "| --- | --- | ---: | --- | ---: | ---: | --- | ---: | ---: |",
    ]
    for r in rows:
        lines.append(
            f"| {r['box']} | {r['method']} | {fmt(r['best_mean'])} ± {fmt(r['best_std'])} | "
            f"{r['best_by_seed']} | {r['simulations_mean']:.0f} | {r['generations']} | "
            f"{r['collapse_generation_by_seed']} | {fmt(r['min_diversity_mean'], 3)} | "
            f"{fmt(r['final_diversity_mean'], 3)} |"
        )
    return [*lines, ""]


def _fronts(results: Results, path: Path) -> Path:
    """Each seed's fronts of every method at the budget, in one figure (a panel per seed)."""
    plt = figures.pyplot()
    seeds = results.plan["seeds"]
    figure, axes = plt.subplots(
        1, len(seeds), figsize=(4.2 * len(seeds) + 1.6, 3.8), squeeze=False, sharey=True
    )
    for ax, seed in zip(axes[0], seeds, strict=True):
        for method in TRADE_METHODS:
            points = sorted(
                (p["measures"]["speed"], p["measures"]["cost_of_transport"])
                for p in results.fronts[("trade", method, seed)]
            )
            ax.step(
                [x for x, _ in points],
                [y for _, y in points],
                where="pre",
                marker="o",
                markersize=3.5,
                lw=1,
                color=COLOURS[method],
                label=method,
            )
        ax.axhline(COT_REFERENCE, color="black", lw=0.6, ls="--")
        ax.set_yscale("log")
        ax.set_title(f"seed {seed}, {results.budgets[seed]:.0f} simulations", fontsize=9)
        ax.set_xlabel("speed (m/s; higher is better)")
    axes[0][0].set_ylabel("cost of transport (1; lower is better)")
    axes[0][-1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    figure.suptitle(
        f"Pareto fronts at the same simulations (dashed: the hypervolume reference, "
        f"{COT_REFERENCE:g})",
        fontsize=9,
    )
    figure.tight_layout()
    return figures.save(figure, path)


def _volumes(results: Results, path: Path) -> Path:
    """Hypervolume against simulations, every run up to the generation it is read at."""
    plt = figures.pyplot()
    figure, ax = plt.subplots(figsize=(7.0, 3.6))
    for method in TRADE_METHODS:
        for n, seed in enumerate(results.plan["seeds"]):
            key = ("trade", method, seed)
            rows = results.curves[key][: results.cuts[key] + 1]
            x = [simulations_at(rows, row["generation"]) for row in rows]
            ax.plot(
                x,
                [row["hypervolume"] for row in rows],
                color=COLOURS[method],
                ls=STYLES[n % len(STYLES)],
                lw=1.1,
                label=method if n == 0 else None,
            )
    ax.set_xlabel("simulations")
    ax.set_ylabel(f"hypervolume (m/s x cost of transport,\nreference (0, {COT_REFERENCE:g}))")
    ax.legend(fontsize=7, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_title("hypervolume of the front so far (line style: seed)", fontsize=9)
    figure.tight_layout()
    return figures.save(figure, path)


def _age(results: Results, path: Path) -> Path:
    """Per box: best speed so far and diversity against simulations, GA and AFPO, per seed."""
    plt = figures.pyplot()
    shapes = results.plan["shapes"]
    figure, axes = plt.subplots(
        2, len(shapes), figsize=(4.0 * len(shapes) + 1.4, 6.0), squeeze=False
    )
    for column, shape in enumerate(shapes):
        box = "x".join(map(str, shape))
        for method in AGE_METHODS:
            for n, seed in enumerate(results.plan["seeds"]):
                rows = results.curves[("age", box, method, seed)]
                x = [simulations_at(rows, row["generation"]) for row in rows]
                style = {"color": AGE_COLOURS[method], "ls": STYLES[n % len(STYLES)], "lw": 1.1}
                label = f"{method}, seed {seed}"
                axes[0][column].plot(x, [r["best_so_far"] for r in rows], label=label, **style)
                axes[1][column].plot(x, [r["diversity"] for r in rows], **style)
        axes[0][column].set_title(box, fontsize=9)
        axes[1][column].axhline(COLLAPSE, color="black", lw=0.6, ls="--")
        axes[1][column].set_ylim(0, 1)
        axes[1][column].set_xlabel("simulations")
    axes[0][0].set_ylabel("best speed so far (m/s)")
    axes[1][0].set_ylabel("diversity (mean pairwise\nHamming distance of the labels)")
    axes[0][-1].legend(fontsize=7, frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    figure.suptitle(
        f"AFPO against the paper's GA on speed alone (dashed: diversity {COLLAPSE:g})", fontsize=9
    )
    figure.tight_layout()
    return figures.save(figure, path)
