"""Tables and figures of `bench/search_experiments.py`'s results (issue 51): the trade-off's
normalised hypervolume at the budget and against simulations, its raw hypervolume beside it,
diversity; the steady-state window's simulations and wall time to the GA's final best."""

from __future__ import annotations

import statistics
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def _mean_std(values: list[float]) -> str:
    return f"{statistics.mean(values):.3f} ± {statistics.pstdev(values):.3f}"


def trade_off_table(results: dict[str, Any]) -> list[str]:
    lines = []
    for preset, seeds in results.get("trade_off", {}).items():
        lines += [
            f"\n{preset}",
            "| method | normalised HV (mean ± std) | by seed | raw HV | "
            "best fitness | final diversity | simulations |",
            "| --- | ---: | --- | ---: | ---: | ---: | ---: |",
        ]
        names = list(next(iter(seeds.values()))["runs"])
        for name in names:
            runs = [seed["runs"][name] for seed in seeds.values()]
            norm = [run["normalised"][-1] for run in runs]
            raw = [run["rows"][-1]["hypervolume"] for run in runs]
            best = [run["rows"][-1]["best"] for run in runs]
            div = [run["rows"][-1]["diversity"] for run in runs]
            sims = [run["rows"][-1]["simulations"] for run in runs]
            lines.append(
                f"| {name} | {_mean_std(norm)} | {' '.join(f'{v:.3f}' for v in norm)} | "
                f"{statistics.mean(raw):.1f} | {statistics.mean(best):.4f} | "
                f"{statistics.mean(div):.3f} | {statistics.mean(sims):.0f} |"
            )
    return lines


def window_table(results: dict[str, Any]) -> list[str]:
    """Simulations and seconds until best so far reaches that seed's GA's final best."""
    lines = []
    for where, seeds in results.get("window", {}).items():
        lines += [
            f"\nwindow, {where}: simulations / seconds to the GA's final best, by seed",
            "| method | by seed | mean simulations | mean seconds | reached |",
            "| --- | --- | ---: | ---: | ---: |",
        ]
        for name in next(iter(seeds.values())):
            cells, hits = [], []
            for seed, found in seeds.items():
                target = found["GA"]["rows"][-1]["best"]
                hit = next((r for r in found[name]["rows"] if r["best"] >= target), None)
                cells.append(
                    f"{seed}: {hit['simulations']}/{hit['seconds']:.0f}s"
                    if hit
                    else f"{seed}: not reached"
                )
                hits += [hit] if hit else []
            sims = statistics.mean(h["simulations"] for h in hits) if hits else float("nan")
            secs = statistics.mean(h["seconds"] for h in hits) if hits else float("nan")
            lines.append(
                f"| {name} | {'; '.join(cells)} | {sims:.0f} | {secs:.1f} | "
                f"{len(hits)} of {len(seeds)} |"
            )
    return lines


def _lines(ax: Any, curves: dict[str, list[tuple[list[float], list[float]]]]) -> None:
    """Each method in one colour: its seeds thin, their mean (each seed's last value at or
    before every x of a common grid) thick, labelled once."""
    for k, (name, seeds) in enumerate(curves.items()):
        for x, y in seeds:
            ax.plot(x, y, lw=0.6, alpha=0.3, color=f"C{k}")
        grid = np.linspace(max(x[0] for x, _ in seeds), min(x[-1] for x, _ in seeds), 200)
        at = [np.asarray(y)[np.searchsorted(x, grid, side="right") - 1] for x, y in seeds]
        ax.plot(grid, np.mean(at, axis=0), lw=2, color=f"C{k}", label=f"{name} (mean)")
    ax.legend(fontsize=7)


def figures(results: dict[str, Any], out: Path) -> None:
    trade = results.get("trade_off", {})
    if trade:
        fig, axes = plt.subplots(1, len(trade), figsize=(6 * len(trade), 4), squeeze=False)
        for ax, (preset, seeds) in zip(axes[0], trade.items(), strict=True):
            names = next(iter(seeds.values()))["runs"]
            _lines(
                ax,
                {
                    name: [
                        (
                            [row["simulations"] for row in seed["runs"][name]["rows"]],
                            seed["runs"][name]["normalised"],
                        )
                        for seed in seeds.values()
                    ]
                    for name in names
                },
            )
            ax.set(title=f"{preset}, 4x4x4", xlabel="simulations", ylabel="normalised hypervolume")
        fig.tight_layout()
        fig.savefig(out / "hypervolume.png", dpi=100)
        plt.close(fig)
    windows = results.get("window", {})
    if windows:
        fig, axes = plt.subplots(1, len(windows), figsize=(6 * len(windows), 4), squeeze=False)
        for ax, (where, seeds) in zip(axes[0], windows.items(), strict=True):
            names = next(iter(seeds.values()))
            _lines(
                ax,
                {
                    name: [
                        (
                            [r["seconds"] for r in found[name]["rows"]],
                            [r["best"] for r in found[name]["rows"]],
                        )
                        for found in seeds.values()
                    ]
                    for name in names
                },
            )
            ax.set(
                xlabel="wall time (s)", ylabel="best speed so far (m/s)", title=f"4x4x4, {where}"
            )
        fig.tight_layout()
        fig.savefig(out / "window.png", dpi=100)
        plt.close(fig)


def report(results: dict[str, Any], out: Path) -> None:
    print("\n".join(trade_off_table(results) + window_table(results)))
    figures(results, out)
