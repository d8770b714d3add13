"""`softevo reproduce --quick`: the whole reproduction, tiny, through a real `softevo serve`."""

from __future__ import annotations

import csv
import json
import sqlite3
import statistics
import subprocess
import sys
from pathlib import Path

import pytest

FIGURES = [
    "fig4a_boxes.png", "fig4b_curve.png", "fig4c_population.png", "fig4d_diversity.png",
    "phase1_breathing_cube.png", "phase2_cube.png", "baselines.png", "encodings.png",
    "ablation.png",
]  # fmt: skip


@pytest.fixture(scope="module")
def results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("reproduce")
    done = subprocess.run(
        [sys.executable, "-m", "softevo.cli", "reproduce", "--quick", "--out", str(out)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    return out


def rows(out: Path) -> list[dict[str, str]]:
    with (out / "results.csv").open() as handle:
        return list(csv.DictReader(handle))


@pytest.mark.slow
def test_every_table_and_figure_is_written(results: Path) -> None:
    experiments = {row["experiment"] for row in rows(results)}
    assert experiments == {"boxes", "phase 2", "encodings", "ablation", "baselines"}
    for name in FIGURES:
        data = (results / name).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 5000, name
    text = (results / "results.md").read_text()
    assert "## boxes" in text and "Phase 1" in text and "Figure 4(b)-(d): run" in text


@pytest.mark.slow
def test_the_table_is_what_the_service_stored(results: Path) -> None:
    """Per box, the best speed over seeds equals the runs' best in the service's database."""
    with sqlite3.connect(results / "softevo.db") as db:
        runs = db.execute(
            "SELECT config, best_fitness, status, sweep_id, evaluations FROM runs"
        ).fetchall()
    swept: dict[str, list[float]] = {}
    for config, best, status, sweep_id, _ in runs:
        if sweep_id is not None:
            assert status == "completed"
            swept.setdefault("x".join(map(str, json.loads(config)["shape"])), []).append(best)
    boxes = [row for row in rows(results) if row["experiment"] == "boxes"]
    assert {row["shape"] for row in boxes} == set(swept) == {"2x2x2", "3x2x2"}
    for row in boxes:
        assert float(row["best_mean"]) == pytest.approx(statistics.fmean(swept[row["shape"]]))
        assert row["completed"] == "2"
    # the baselines ran on the GA's evaluation budget (within a generation's worth)
    table = {(row["experiment"], row["variant"]): row for row in rows(results)}
    budget = float(next(r for r in boxes if r["shape"] == "2x2x2")["evaluations_mean"])
    for variant in ("random search", "hill climber"):
        spent = float(table["baselines", variant]["evaluations_mean"])
        assert abs(spent - budget) <= 6, (variant, spent, budget)
