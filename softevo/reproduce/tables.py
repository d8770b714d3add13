"""results.csv and results.md: one row per experiment, variant and box."""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

# -- outputs ---------------------------------------------------------------------------------------

COLUMNS = [
    "experiment",
    "variant",
    "shape",
    "seeds",
    "completed",
    "best_mean",
    "best_std",
    "best_min",
    "best_max",
    "best_by_seed",
    "evaluations_mean",
    "population",
    "generations",
    "wall_seconds_mean",
    "budget",
    "budget_best_mean",
    "budget_best_std",
]


def fmt(value: Any, digits: int = 4) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def write_tables(
    rows: list[dict[str, Any]], out: Path, notes: list[str], appendix: Sequence[str] = ()
) -> None:
    with (out / "results.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    lines = ["# softevo reproduce: results", "", *notes, ""]
    for experiment in dict.fromkeys(r["experiment"] for r in rows):
        group = [r for r in rows if r["experiment"] == experiment]
        budgeted = any(r["budget"] is not None for r in group)
        extra = " best within the GA's simulations: mean (std) | GA's simulations |"
        lines += [
            f"## {experiment}",
            "",
            "| variant | box | seeds | best speed mean (m/s) | spread (std) | min | max "
            "| simulations (mean) | wall per run (s) |" + (extra if budgeted else ""),
            "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |"
            + (" ---: | ---: |" if budgeted else ""),
        ]
        for r in group:
            line = (
                f"| {r['variant']} | {r['shape']} | {r['seeds']} | {fmt(r['best_mean'])} "
                f"| {fmt(r['best_std'])} | {fmt(r['best_min'])} | {fmt(r['best_max'])} "
                f"| {fmt(r['evaluations_mean'], 0)} | {fmt(r['wall_seconds_mean'], 1)} |"
            )
            if budgeted:
                within = (
                    f"{fmt(r['budget_best_mean'])} ({fmt(r['budget_best_std'])})"
                    if r["budget_best_mean"] is not None
                    else "-"
                )
                line += f" {within} | {fmt(r['budget'], 0)} |"
            lines.append(line)
        lines.append("")
    lines += appendix
    (out / "results.md").write_text("\n".join(lines))
