"""`softevo reproduce --quick`: the whole reproduction, tiny, through a real `softevo serve`, run
once, by the installed wheel from a folder that is not the repository (`installed.py`: nothing may
be read from the checkout, issue 19); `--resume` by the checkout's own."""

from __future__ import annotations

import csv
import json
import math
import shutil
import sqlite3
import statistics
import subprocess
import sys
from pathlib import Path

import pytest

from tests.softevo.installed import clean_env, install_wheel

FIGURES = [
    "fig4a_boxes.png",
    "fig4b_curve.png",
    "fig4c_population.png",
    "fig4d_diversity.png",
    "phase1_breathing_cube.png",
    "phase2_cube.png",
    "baselines.png",
    "encodings.png",
    "ablation.png",
    "ablation_curves.png",
    "clock.png",
]


def reproduce(out: Path, *flags: str) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(
        [
            sys.executable,
            "-P",
            "-m",
            "softevo.cli",
            "reproduce",
            "--quick",
            "--out",
            str(out),
            *flags,
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return done


@pytest.fixture(scope="module")
def results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The installed wheel's `softevo reproduce --quick` (one pool process: it compiles the
    physics kernels for its own copy of the sources)."""
    venv = install_wheel(tmp_path_factory.mktemp("installed"))
    out, elsewhere = tmp_path_factory.mktemp("reproduce"), tmp_path_factory.mktemp("cwd")
    done = subprocess.run(
        [
            str(venv / "bin" / "softevo"),
            "reproduce",
            "--quick",
            "--workers",
            "1",
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        cwd=elsewhere,
        env=clean_env(),
        timeout=600,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return out


def rows(out: Path) -> list[dict[str, str]]:
    with (out / "results.csv").open() as handle:
        return list(csv.DictReader(handle))


@pytest.mark.slow
def test_every_table_and_figure_is_written(results: Path) -> None:
    experiments = {row["experiment"] for row in rows(results)}
    assert experiments == {"boxes", "clock", "phase 2", "encodings", "ablation", "baselines"}
    for name in FIGURES:
        data = (results / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000, name
    # each box's fastest robot, simulated again: the run's own time gives the stored best
    with (results / "champions.csv").open() as handle:
        champions = list(csv.DictReader(handle))
    assert [(row["experiment"], row["shape"]) for row in champions] == [
        ("boxes", "2x2x2"),
        ("boxes", "3x2x2"),
        ("clock", "2x2x2"),
        ("clock", "3x2x2"),
    ]
    for row in champions:
        assert float(row["speed_1x"]) == float(row["stored_best"])
        table = {r["shape"]: r for r in rows(results) if r["experiment"] == row["experiment"]}
        assert float(row["stored_best"]) == float(table[row["shape"]]["best_max"])
        prefix = "best" if row["experiment"] == "boxes" else "best_fast"
        robot = json.loads((results / f"{prefix}_{row['shape']}.json").read_text())
        assert robot["format"] == "softevo.robot/1"
        assert "x".join(map(str, robot["shape"])) == row["shape"]
        # the clock's robots were evolved, and are replayed, at 2 pi rad/s
        omega = 2 * math.pi if row["experiment"] == "clock" else 1.0
        assert robot["sim"]["omega"] == pytest.approx(omega) == float(row["omega"])
    text = (results / "results.md").read_text()
    assert "## boxes" in text and "Phase 1" in text and "Figure 4(b)-(d): run" in text
    assert "## champions, simulated for longer" in text


@pytest.mark.slow
def test_the_table_is_what_the_service_stored(results: Path) -> None:
    """Per box, the best speed over seeds equals the runs' best in the service's database."""
    with sqlite3.connect(results / "softevo.db") as db:
        runs = db.execute(
            "SELECT config, best_fitness, status, sweep_id, evaluations FROM runs"
        ).fetchall()
    swept: dict[tuple[str, str], list[float]] = {}  # (experiment, box): bests
    for config, best, status, sweep_id, _ in runs:
        if sweep_id is not None:
            assert status == "completed"
            settings = json.loads(config)
            experiment = "clock" if settings["sim"]["omega"] != 1.0 else "boxes"
            box = "x".join(map(str, settings["shape"]))
            swept.setdefault((experiment, box), []).append(best)
    assert set(swept) == {(e, b) for e in ("boxes", "clock") for b in ("2x2x2", "3x2x2")}
    for row in rows(results):
        if row["experiment"] in ("boxes", "clock"):
            bests = swept[row["experiment"], row["shape"]]
            assert float(row["best_mean"]) == pytest.approx(statistics.fmean(bests))
            assert row["completed"] == "2"
    boxes = [row for row in rows(results) if row["experiment"] == "boxes"]
    # the focus box's GA: the sweep's seeds and one more; the same runs in both of its tables
    table = {(row["experiment"], row["variant"]): row for row in rows(results)}
    ga = table["baselines", "GA (paper-voxel)"]
    assert ga["seeds"] == table["ablation", "paper settings"]["seeds"] == "1 2 3"
    assert ga["best_mean"] == table["ablation", "paper settings"]["best_mean"]
    # the baselines ran on the GA's simulations (within a generation's worth)
    budget = float(ga["evaluations_mean"])
    for variant in ("random search", "hill climber"):
        assert table["baselines", variant]["seeds"] == "1 2 3"
        spent = float(table["baselines", variant]["evaluations_mean"])
        assert abs(spent - budget) <= 6, (variant, spent, budget)
    # and every variant's best within the GA's simulations is at most its best
    encodings_budget = float(next(r for r in boxes if r["shape"] == "2x2x2")["evaluations_mean"])
    for row in rows(results):
        if row["experiment"] in ("boxes", "clock", "phase 2") or "paper" in row["variant"]:
            assert row["budget"] == "", row
            continue
        expected = encodings_budget if row["experiment"] == "encodings" else budget
        assert float(row["budget"]) == pytest.approx(expected)
        assert float(row["budget_best_mean"]) <= float(row["best_mean"]) + 1e-12


@pytest.mark.slow
def test_resume_reuses_every_finished_run(results: Path, tmp_path: Path) -> None:
    """A second invocation with --resume simulates nothing new and writes the same table."""
    copy = tmp_path / "again"
    shutil.copytree(results, copy)
    with sqlite3.connect(results / "softevo.db") as db:
        total = db.execute("SELECT count(*) FROM runs").fetchone()[0]
    done = reproduce(copy, "--resume")
    assert (
        f"runs through the REST API ({total} of them reused" in (copy / "results.md").read_text()
    ), done.stdout
    with sqlite3.connect(copy / "softevo.db") as db:
        assert db.execute("SELECT count(*) FROM runs").fetchone()[0] == total
    keep = ("experiment", "variant", "shape", "seeds", "best_mean", "evaluations_mean")
    assert [{k: r[k] for k in keep} for r in rows(copy)] == [
        {k: r[k] for k in keep} for r in rows(results)
    ]
