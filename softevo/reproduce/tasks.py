"""`softevo reproduce --tasks`: the task suite (core/robots/tasks.py) through the API, the GA
against random search on the same budget.

One `POST /sweeps` over every task x seeds 1-3 (paper-voxel's GA, 4x4x4, 25 x 100); once a task's
GA runs are done, random search on that task gets their mean number of simulations (25 new random
genomes a generation). Writes tasks.csv, tasks.md and tasks.png into --out.
"""

from __future__ import annotations

import csv
import statistics
from pathlib import Path
from typing import Any

from softevo.client import Client
from softevo.core.objectives import OBJECTIVES, objective_label
from softevo.core.robots.tasks import TASKS
from softevo.reproduce.client import wait_runs
from softevo.reproduce.tables import fmt

FULL_SUITE: dict[str, Any] = {"seeds": [1, 2, 3]}
QUICK_SUITE: dict[str, Any] = {
    "seeds": [1],
    "population": 6,
    "generations": 3,
    "shapes": [[2, 2, 2]],
    "sim": {"duration": 1.5, "settle_time": 0.5},
}
COLUMNS = [
    "task",
    "objective",
    "unit",
    "ga_best_by_seed",
    "ga_best_mean",
    "ga_best_std",
    "random_best_by_seed",
    "random_best_mean",
    "random_best_std",
    "ga_minus_random",
    "ga_evaluations_mean",
    "random_evaluations_mean",
    "ga_wins",
]


def run_suite(client: Client, quick: bool) -> list[dict[str, Any]]:
    """Every task's GA runs and random-search runs, finished: one row per task."""
    suite = QUICK_SUITE if quick else FULL_SUITE
    sweep = client.sweep(**suite, tasks=list(TASKS)).data
    groups = {group["task"]: group["run_ids"] for group in sweep["boxes"]}
    ga = {task: wait_runs(client, ids, "tasks") for task, ids in groups.items()}
    base = {key: value for key, value in suite.items() if key not in ("seeds", "shapes")}
    if "shapes" in suite:
        base["shape"] = suite["shapes"][0]
    random_ids: dict[str, list[int]] = {}
    for task, runs in ga.items():
        population = runs[0]["config"]["population"]
        budget = statistics.fmean(r["progress"]["evaluations"] for r in runs)
        random_ids[task] = [
            client.run(
                **{
                    **base,
                    "preset": task,
                    "seed": run["seed"],
                    "algorithm": "random",
                    "population": population,
                    "generations": max(1, round(budget / population)),
                }
            ).id
            for run in runs
        ]
    random = {task: wait_runs(client, ids, "tasks") for task, ids in random_ids.items()}
    return [_row(task, ga[task], random[task]) for task in TASKS]


def _best(runs: list[dict[str, Any]]) -> list[float]:
    return [
        r["progress"]["best_fitness"] for r in runs if r["progress"]["best_fitness"] is not None
    ]


def _row(task: str, ga: list[dict[str, Any]], random: list[dict[str, Any]]) -> dict[str, Any]:
    objective = TASKS[task][2]
    ga_best, random_best = _best(ga), _best(random)
    by_seed = {r["seed"]: r["progress"]["best_fitness"] for r in random}
    wins = sum(
        1
        for r in ga
        if r["progress"]["best_fitness"] is not None
        and by_seed.get(r["seed"]) is not None
        and r["progress"]["best_fitness"] > by_seed[r["seed"]]
    )
    mean = statistics.fmean
    return {
        "task": task,
        "objective": objective,
        "unit": OBJECTIVES[objective][1],
        "ga_best_by_seed": " ".join(f"{b:.4f}" for b in ga_best),
        "ga_best_mean": mean(ga_best) if ga_best else None,
        "ga_best_std": statistics.pstdev(ga_best) if ga_best else None,
        "random_best_by_seed": " ".join(f"{b:.4f}" for b in random_best),
        "random_best_mean": mean(random_best) if random_best else None,
        "random_best_std": statistics.pstdev(random_best) if random_best else None,
        "ga_minus_random": mean(ga_best) - mean(random_best) if ga_best and random_best else None,
        "ga_evaluations_mean": mean(r["progress"]["evaluations"] for r in ga),
        "random_evaluations_mean": mean(r["progress"]["evaluations"] for r in random),
        "ga_wins": f"{wins}/{len(ga)}",
    }


def write_suite(rows: list[dict[str, Any]], out: Path, command: str, wall: float) -> list[Path]:
    """tasks.csv, tasks.md and tasks.png (GA against random search, per task)."""
    with (out / "tasks.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    lines = [
        "# The task suite: the GA against random search on the same budget",
        "",
        "| task | objective | GA best (mean ± std) | random search best (mean ± std) | GA - random "
        "| GA beats random (seeds) | simulations GA / random |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    for row in rows:
        lines.append(
            f"| {row['task']} | {objective_label(row['objective'])} | "
            f"{fmt(row['ga_best_mean'])} ± {fmt(row['ga_best_std'])} | "
            f"{fmt(row['random_best_mean'])} ± {fmt(row['random_best_std'])} | "
            f"{fmt(row['ga_minus_random'])} | {row['ga_wins']} | "
            f"{row['ga_evaluations_mean']:.0f} / {row['random_evaluations_mean']:.0f} |"
        )
    lines += ["", f"Command: `{command}`; {wall:.0f} s.", ""]
    (out / "tasks.md").write_text("\n".join(lines))
    return [out / "tasks.csv", out / "tasks.md", _figure(rows, out / "tasks.png")]


def _figure(rows: list[dict[str, Any]], path: Path) -> Path:
    from softevo.core.outputs import figures

    plt = figures.pyplot()
    figure, axes = plt.subplots(1, len(rows), figsize=(2.3 * len(rows), 3.2))
    for ax, row in zip(axes, rows, strict=True):
        for x, (name, colour) in enumerate((("ga", "tab:blue"), ("random", "tab:gray"))):
            values = [float(v) for v in row[f"{name}_best_by_seed"].split()]
            ax.bar(x, statistics.fmean(values) if values else 0, color=colour, alpha=0.6)
            ax.scatter([x] * len(values), values, color="black", s=10, zorder=3)
        ax.set_xticks([0, 1], ["GA", "random"])
        ax.set_title(row["task"].removeprefix("task-"), fontsize=10)
        ax.set_ylabel(objective_label(row["objective"]), fontsize=8)
        ax.axhline(0, color="black", lw=0.5)
    figure.suptitle("best fitness after the GA's budget (bars: mean; dots: seeds)", fontsize=10)
    figure.tight_layout()
    return figures.save(figure, path)
