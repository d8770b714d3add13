"""Phase 1 (the breathing cube, one robot simulated here) and the champions of each box
simulated again for longer."""

from __future__ import annotations

import csv
import json
from importlib import resources
from pathlib import Path
from typing import Any

from softevo.core.outputs import figures
from softevo.reproduce.experiments import Experiments
from softevo.reproduce.plan import CLOCK
from softevo.reproduce.tables import fmt

# -- phase 1 ---------------------------------------------------------------------------------------


def shipped_robot_text(name: str) -> str:
    """A robot file shipped inside the package (an installed softevo has no examples/ folder)."""
    return resources.files("softevo.reproduce").joinpath("data", name).read_text(encoding="utf-8")


def breathing_cube(out: Path, quick: bool) -> dict[str, Any]:
    """The paper's phase 1: the shipped breathing cube, simulated here (one robot, no evolution)."""
    from softevo.core.physics import simulate
    from softevo.core.robots.robot_file import parse_robot, with_sim

    robot = parse_robot(json.loads(shipped_robot_text("breathing_cube.json")))
    if quick:
        robot = with_sim(robot, duration=2.0)
    result, trajectory = simulate(robot, record_every=max(1, round(1 / (100 * robot.sim.step))))
    assert trajectory is not None
    heights = trajectory.frames[:, :, 2].mean(axis=1)
    xs = trajectory.frames[:, :, 0].mean(axis=1)
    plt = figures.pyplot()
    figure, axes = plt.subplots(figsize=(7.5, 3.0))
    axes.plot(trajectory.times, heights, label="centre of mass height (m)")
    axes.plot(trajectory.times, xs - xs[0], label="centre of mass x shift (m)")
    axes.set_xlabel("time (s)")
    axes.set_ylabel("m")
    axes.set_title("phase 1: breathing cube (1x1x1, not evolved), on flat ground")
    axes.legend(frameon=False, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    figure.tight_layout()
    figures.save(figure, out / "phase1_breathing_cube.png")
    return {
        "speed": result.speed,
        "distance": result.distance,
        "stable": result.stable,
        "final_height": float(heights[-1]),
        "duration": robot.sim.duration,
    }


# -- the champions, simulated for longer ----------------------------------------------------------

LONGER = (1, 3, 6)  # multiples of the run's simulated time


def champions(experiments: Experiments, out: Path) -> list[dict[str, Any]]:
    """The fastest robot of each box, at the paper's actuation and at FAST_OMEGA
    (`GET /runs/{id}/best`, saved as best_<box>.json and best_fast_<box>.json), simulated in
    this process for 1x (the fitness the run stored, as a check), 3x and 6x the run's time: a
    fitness clock of a few actuation periods can reward a transient lunge, and this shows
    which robots keep their speed."""
    from softevo.core.physics import simulate
    from softevo.core.robots.robot_file import parse_robot, with_sim

    rows = []
    for (experiment, variant), prefix in (
        ((("boxes", "paper-voxel")), "best"),
        (CLOCK, "best_fast"),
    ):
        for shape in experiments.plan.boxes:
            group = experiments.group(experiment, variant, shape)
            done = [r for r in group.runs if r["progress"]["best_fitness"] is not None]
            if not done:
                continue
            run = max(done, key=lambda r: r["progress"]["best_fitness"])
            data = experiments.client.get_run(run["id"]).best()
            box = "x".join(map(str, shape))
            (out / f"{prefix}_{box}.json").write_text(json.dumps(data, indent=1) + "\n")
            robot = parse_robot(data)
            row: dict[str, Any] = {
                "experiment": experiment,
                "omega": robot.sim.omega,
                "shape": box,
                "run": run["id"],
                "seed": run["seed"],
                "stored_best": run["progress"]["best_fitness"],
                "voxels": sum(label != "empty" for label in data["voxels"]),
            }
            for factor in LONGER:
                duration = robot.sim.duration * factor
                result, _ = simulate(with_sim(robot, duration=duration))
                row[f"speed_{factor}x"] = result.speed
                row[f"duration_{factor}x"] = duration
            rows.append(row)
    with (out / "champions.csv").open("w", newline="") as handle:
        columns = list(rows[0]) if rows else ["shape"]
        writer = csv.DictWriter(handle, fieldnames=columns, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    return rows


def champions_table(rows: list[dict[str, Any]]) -> list[str]:
    if not rows:
        return []
    durations = [f"{rows[0][f'duration_{f}x']:g} s" for f in LONGER]
    return [
        "## champions, simulated for longer",
        "",
        "The fastest robot of each box, at the paper's actuation (boxes) and at 2 pi rad/s "
        "(clock): best_<box>.json and best_fast_<box>.json, simulated again in process for the "
        "run's own time (the first speed must equal the stored best) and longer.",
        "",
        "| experiment | omega (rad/s) | box | run | seed | voxels | stored best (m/s) | "
        + " | ".join(f"speed over {d} (m/s)" for d in durations)
        + " |",
        "| --- | ---: | --- | ---: | ---: | ---: | ---: |" + " ---: |" * len(LONGER),
        *(
            f"| {r['experiment']} | {r['omega']:.4g} | {r['shape']} | {r['run']} | {r['seed']} "
            f"| {r['voxels']} | {fmt(r['stored_best'])} | "
            + " | ".join(fmt(r[f"speed_{f}x"]) for f in LONGER)
            + " |"
            for r in rows
        ),
        "",
    ]
