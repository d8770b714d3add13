"""`softevo reproduce --tasks --quick`: the task suite end to end through a private service."""

from __future__ import annotations

import csv
from pathlib import Path

from softevo.cli import main
from softevo.core.tasks import TASKS


def test_the_task_suite_runs_every_task_against_random_search(tmp_path: Path) -> None:
    assert main(["reproduce", "--tasks", "--quick", "--out", str(tmp_path)]) == 0
    with (tmp_path / "tasks.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [row["task"] for row in rows] == list(TASKS)
    for row in rows:
        assert row["objective"] == TASKS[row["task"]][2]
        assert float(row["ga_evaluations_mean"]) > 0 and float(row["random_evaluations_mean"]) > 0
        assert row["ga_best_mean"] and row["random_best_mean"]
    assert (tmp_path / "tasks.png").stat().st_size > 10_000
    assert "random search" in (tmp_path / "tasks.md").read_text()
