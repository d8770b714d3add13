"""`softevo reproduce --qd`: quality-diversity and co-design through the API, on three of the
paper's boxes (4x4x3, 4x4x4, 3x3x6) x seeds 1-3 (paper-voxel, 25 robots a generation):

* `ga`: the paper's GA for 100 generations, keeping a MAP-Elites archive beside it (voxels x
  actuated, 8 x 8) that does not change its breeding, so its coverage can be compared;
* `map-elites`: MAP-Elites on the same archive with the GA's simulation budget (that seed's GA
  simulations / 25 generations);
* `voxel-phase`: the GA with every actuated voxel's own phase and amplitude (co-design), 100
  generations, with the same archive beside it.

Writes qd.csv, qd.md, qd.png and qd_archives.png into --out.
"""

from __future__ import annotations

import csv
import statistics
from pathlib import Path
from typing import Any

from softevo.client import Client
from softevo.reproduce.client import wait_runs
from softevo.reproduce.tables import fmt

QD: dict[str, Any] = {"descriptors": ["voxels", "actuated"], "bins": [8, 8]}
FULL: dict[str, Any] = {"shapes": [[4, 4, 3], [4, 4, 4], [3, 3, 6]], "seeds": [1, 2, 3]}
QUICK: dict[str, Any] = {
    "shapes": [[2, 2, 2]],
    "seeds": [1],
    "settings": {"population": 6, "generations": 3, "sim": {"duration": 1.5, "settle_time": 0.5}},
}
VARIANTS = ("ga", "map-elites", "voxel-phase")
#: An elite "reaches the best" when its speed is at least this fraction of the best speed any
#: variant found on that box and seed.
NEAR_BEST = 0.8
COLUMNS = [
    "box",
    "variant",
    "best_by_seed",
    "best_mean",
    "best_std",
    "coverage_mean",
    "qd_score_mean",
    "near_best_cells_mean",
    "simulations_mean",
]


def run_qd(client: Client, quick: bool) -> tuple[list[dict[str, Any]], dict[tuple, Any]]:
    """Every variant's runs, finished: rows per (box, variant), and each run's archive by
    (box, variant, seed)."""
    plan = QUICK if quick else FULL
    base = {"preset": "paper-voxel", **plan.get("settings", {}), **QD}
    keys = [(tuple(shape), seed) for shape in plan["shapes"] for seed in plan["seeds"]]
    submitted: dict[tuple, int] = {}
    for shape, seed in keys:
        common = {**base, "shape": list(shape), "seed": seed}
        submitted[(shape, "ga", seed)] = client.run(**common).id
        submitted[(shape, "voxel-phase", seed)] = client.run(**common, encoding="voxel-phase").id
    done = dict(zip(submitted, wait_runs(client, list(submitted.values()), "qd"), strict=True))
    elites: dict[tuple, int] = {}
    for shape, seed in keys:  # MAP-Elites gets that seed's GA budget, in generations of P
        ga = done[(shape, "ga", seed)]
        population = ga["config"]["population"]
        generations = max(1, round(ga["progress"]["evaluations"] / population))
        elites[(shape, "map-elites", seed)] = client.run(
            **{
                **base,
                "shape": list(shape),
                "seed": seed,
                "algorithm": "map-elites",
                "generations": generations,
            }
        ).id
    done.update(zip(elites, wait_runs(client, list(elites.values()), "qd"), strict=True))
    archives = {key: client.get(f"/runs/{run['id']}/archive") for key, run in done.items()}
    rows = [
        _row(
            shape,
            variant,
            [
                (
                    done[(shape, variant, s)],
                    archives[(shape, variant, s)],
                    _reference(done, shape, s),
                )
                for s in plan["seeds"]
            ],
        )
        for shape in dict.fromkeys(shape for shape, _ in keys)
        for variant in VARIANTS
    ]
    return rows, archives


def _reference(done: dict[tuple, Any], shape: tuple, seed: int) -> float:
    """The best speed any variant found on this box and seed."""
    return max(done[(shape, v, seed)]["progress"]["best_fitness"] or 0.0 for v in VARIANTS)


def _row(shape: tuple, variant: str, runs: list[tuple[dict, dict, float]]) -> dict[str, Any]:
    best = [run["progress"]["best_fitness"] or 0.0 for run, _, _ in runs]  # failed: no best
    near = [sum(c["fitness"] >= NEAR_BEST * ref for c in a["cells"]) for _, a, ref in runs]
    mean = statistics.fmean
    return {
        "box": "x".join(map(str, shape)),
        "variant": variant,
        "best_by_seed": " ".join(f"{b:.4f}" for b in best),
        "best_mean": mean(best),
        "best_std": statistics.pstdev(best),
        "coverage_mean": mean(a["coverage"] for _, a, _ in runs),
        "qd_score_mean": mean(a["qd_score"] for _, a, _ in runs),
        "near_best_cells_mean": mean(near),
        "simulations_mean": mean(run["progress"]["evaluations"] for run, _, _ in runs),
    }


def write_qd(
    rows: list[dict[str, Any]], archives: dict[tuple, Any], out: Path, command: str, wall: float
) -> list[Path]:
    """qd.csv, qd.md, qd.png (per box and variant) and qd_archives.png (seed 1's archives)."""
    with (out / "qd.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, COLUMNS, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    lines = [
        "# Quality-diversity and co-design: MAP-Elites and voxel-phase against the GA",
        "",
        "| box | variant | best speed, m/s (mean ± std) | coverage | QD-score | cells >= 80 % "
        "of the best | simulations |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    for row in rows:
        lines.append(
            f"| {row['box']} | {row['variant']} | {fmt(row['best_mean'])} ± "
            f"{fmt(row['best_std'])} | {fmt(row['coverage_mean'], 3)} | "
            f"{fmt(row['qd_score_mean'], 3)} | {row['near_best_cells_mean']:.1f} | "
            f"{row['simulations_mean']:.0f} |"
        )
    lines += ["", f"Command: `{command}`; {wall:.0f} s.", ""]
    (out / "qd.md").write_text("\n".join(lines))
    return [
        out / "qd.csv",
        out / "qd.md",
        _bars(rows, out / "qd.png"),
        _archives(archives, out / "qd_archives.png"),
    ]


def _bars(rows: list[dict[str, Any]], path: Path) -> Path:
    from softevo.core.outputs import figures

    plt = figures.pyplot()
    boxes = list(dict.fromkeys(row["box"] for row in rows))
    measures = (
        ("best_mean", "best speed (m/s)"),
        ("coverage_mean", "archive coverage"),
        ("qd_score_mean", "QD-score (sum of elites' speed, m/s)"),
    )
    figure, axes = plt.subplots(1, 3, figsize=(11, 3.4))
    width = 0.8 / len(VARIANTS)
    colours = {"ga": "tab:blue", "map-elites": "tab:green", "voxel-phase": "tab:orange"}
    for ax, (key, label) in zip(axes, measures, strict=True):
        for k, variant in enumerate(VARIANTS):
            values = [
                next(r[key] for r in rows if r["box"] == b and r["variant"] == variant)
                for b in boxes
            ]
            positions = [i + (k - 1) * width for i in range(len(boxes))]
            ax.bar(positions, values, width, label=variant, color=colours[variant])
        ax.set_xticks(range(len(boxes)), boxes)
        ax.set_xlabel("bounding box")
        ax.set_ylabel(label)
    axes[0].legend(fontsize=8)
    figure.suptitle(
        "mean over seeds; MAP-Elites on the GA's simulation budget; archive: "
        "voxels x actuated, 8 x 8",
        fontsize=9,
    )
    figure.tight_layout()
    return figures.save(figure, path)


def _archives(archives: dict[tuple, Any], path: Path) -> Path:
    """Seed 1's archive of each variant on the middle box, as heat maps on one colour scale."""
    import numpy as np

    from softevo.core.outputs import figures
    from softevo.core.outputs.archive_figures import archive_grid

    plt = figures.pyplot()
    shapes = list(dict.fromkeys(shape for shape, _, _ in archives))
    shape = shapes[len(shapes) // 2]
    seed = min(seed for _, _, seed in archives)
    chosen = {v: archives[(shape, v, seed)] for v in VARIANTS}
    grids = {
        v: archive_grid(
            {
                "bins": [a["descriptors"][0]["bins"], a["descriptors"][1]["bins"]],
                "elites": a["cells"],
            }
        )
        for v, a in chosen.items()
    }
    high = max(float(np.nanmax(g)) if np.isfinite(g).any() else 0.0 for g in grids.values())
    figure, axes = plt.subplots(1, 3, figsize=(11, 3.6))
    for ax, (variant, grid) in zip(axes, grids.items(), strict=True):
        image = ax.imshow(
            grid.T,
            origin="lower",
            extent=[0, 1, 0, 1],
            vmin=0,
            vmax=high,
            cmap="viridis",
            interpolation="none",
            aspect="auto",
        )
        ax.grid(False)
        ax.set_title(f"{variant}: {int(np.isfinite(grid).sum())} of {grid.size} cells", fontsize=9)
        ax.set_xlabel("voxels (filled fraction of the box)")
    axes[0].set_ylabel("actuated fraction of the filled voxels")
    figure.colorbar(image, ax=list(axes), label="elite's speed (m/s)")
    figure.suptitle(f"archives after the run, {'x'.join(map(str, shape))}, seed {seed}", fontsize=9)
    return figures.save(figure, path)
