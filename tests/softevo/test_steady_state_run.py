"""`softevo run --algorithm steady-state`: stopped with Ctrl-C mid-run (births in flight) or
after fewer generations, `--resume` goes on to the curve of the uninterrupted run."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.softevo.inprocess import softevo
from tests.softevo.test_run_command import AS_A_SHELL_STARTS_IT

RUN = (
    "run",
    "--preset",
    "quick",
    "--population",
    "8",
    "--shape",
    "2x2x2",
    "--seed",
    "9",
    "--algorithm",
    "steady-state",
    "--options",
    '{"window": 5}',
)


def _curve(folder: Path) -> list[dict]:
    return json.loads((folder / "curve.json").read_text())["generations"]


def test_a_run_resumed_with_more_generations_has_the_longer_runs_births(tmp_path: Path) -> None:
    whole, short = tmp_path / "whole", tmp_path / "short"
    for folder, workers, generations in ((str(whole), "1", "6"), (str(short), "2", "2")):
        done = softevo(*RUN, "--workers", workers, "--generations", generations, "--out", folder)
        assert done.returncode == 0, done.stderr
    resumed = softevo("run", "--resume", str(short), "--generations", "6", "--workers", "2")
    assert resumed.returncode == 0, resumed.stderr
    assert _curve(short) == _curve(whole) and len(_curve(whole)) == 6
    assert (short / "state.json").read_text() == (whole / "state.json").read_text()


def test_ctrl_c_mid_run_then_resume_gives_the_uninterrupted_curve(tmp_path: Path) -> None:
    whole, stopped = tmp_path / "whole", tmp_path / "stopped"
    long = ("--generations", "40", "--duration", "2")
    assert softevo(*RUN, *long, "--workers", "1", "--out", str(whole)).returncode == 0
    command = [
        sys.executable,
        "-P",
        "-c",
        AS_A_SHELL_STARTS_IT,
        sys.executable,
        "-P",
        "-m",
        "softevo.cli",
        *RUN,
        *long,
        "--workers",
        "2",
        "--out",
        str(stopped),
    ]
    process = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    started = time.monotonic()
    while not (stopped / "curve.csv").exists() and time.monotonic() < started + 120:
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGINT)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, stderr
    assert 1 <= len(_curve(stopped)) < 40  # stopped with births of a row in flight
    resumed = softevo("run", "--resume", str(stopped), "--workers", "1")
    assert resumed.returncode == 0, resumed.stderr
    assert _curve(stopped) == _curve(whole)


def _renumbered(window: list[dict]) -> None:
    window[2]["n"] = 99


@pytest.mark.parametrize(
    ("tamper", "ending"),
    [
        (
            _renumbered,
            "data.steady.window[2]: expected birth 10 with saved true or false, got birth 99",
        ),
        (list.pop, "data.steady.window: expected a list of 5 births (the window), got 4"),
    ],
)
def test_a_tampered_window_is_refused_in_one_line(
    tmp_path: Path, tamper: Callable[[list[dict]], object], ending: str
) -> None:
    folder = tmp_path / "run"
    done = softevo(*RUN, "--workers", "1", "--generations", "1", "--out", str(folder))
    assert done.returncode == 0, done.stderr
    (folder / "run.db").unlink()  # as the release before the store left it: state.json is read
    state = json.loads((folder / "state.json").read_text())
    tamper(state["data"]["steady"]["window"])
    (folder / "state.json").write_text(json.dumps(state))
    refused = softevo("run", "--resume", str(folder), "--generations", "3")
    assert refused.returncode == 2
    assert refused.stderr.strip().endswith(ending)
