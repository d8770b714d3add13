"""`softevo reproduce --tasks --quick`: the task suite end to end through a private service."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from softevo.cli import main
from softevo.core.robots.tasks import TASKS
from softevo.local_service import free_port, service_env, start_service


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


def test_a_service_that_is_not_there_is_one_line(tmp_path: Path) -> None:
    url = f"http://127.0.0.1:{free_port()}"
    with pytest.raises(SystemExit) as exited:
        main(["reproduce", "--tasks", "--quick", "--out", str(tmp_path), "--url", url])
    assert str(exited.value.code).startswith(f"softevo reproduce: error: {url}: POST {url}/sweeps")


def test_a_refusal_is_the_apis_own_words(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A wrong SOFTEVO_API_TOKEN: the command stops at the first POST with the API's message."""
    env = service_env(database_url=f"sqlite:///{tmp_path / 'softevo.db'}", api_token="right")
    with start_service(env, tmp_path / "service.log", "--log-level", "warning") as service:
        monkeypatch.setenv("SOFTEVO_API_TOKEN", "wrong")
        with pytest.raises(SystemExit) as exited:
            main(["reproduce", "--tasks", "--quick", "--out", str(tmp_path), "--url", service.url])
    assert exited.value.code == "softevo reproduce: POST /sweeps answered 403: wrong bearer token"
