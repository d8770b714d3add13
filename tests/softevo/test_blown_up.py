"""A robot whose simulation blows up (too large a `sim.dt`) through the commands a user runs:
`softevo simulate` prints strict JSON (null, never NaN tokens) and says why it exits 1 in one
line; `softevo replay` draws it until it blew up, never a traceback."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from PIL import Image

from softevo.core.outputs.picture import hold_last_finite
from tests.softevo.inprocess import softevo


def _blowing_up(examples: Path, tmp_path: Path) -> Path:
    robot = json.loads((examples / "crawler_4x4x4.json").read_text())
    robot["sim"] = {**robot["sim"], "dt": 0.003, "duration": 1.0, "settle_time": 0.1}
    path = tmp_path / "blows_up.json"
    path.write_text(json.dumps(robot))
    return path


def test_simulate_prints_strict_json_and_one_line_why(examples: Path, tmp_path: Path) -> None:
    robot = _blowing_up(examples, tmp_path)
    done = softevo("simulate", str(robot))
    assert done.returncode == 1
    measures = json.loads(done.stdout, parse_constant=lambda token: 1 / 0)  # NaN: fails
    assert measures["stable"] is False
    assert measures["com_end"] == [None, None, None] and measures["speed"] is None
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "blew up" in lines[0] and "sim.dt" in lines[0], done.stderr


def test_its_trajectory_file_is_strict_json_up_to_the_blow_up(
    examples: Path, tmp_path: Path
) -> None:
    out = tmp_path / "trajectory.json"
    done = softevo("simulate", str(_blowing_up(examples, tmp_path)), "--trajectory", str(out))
    assert done.returncode == 1
    trajectory = json.loads(out.read_text(), parse_constant=lambda token: 1 / 0)
    assert trajectory["blew_up_at"] > 0 and len(trajectory["frames"]) >= 1
    assert trajectory["times"][-1] < trajectory["blew_up_at"]


def test_replay_draws_a_robot_that_blew_up_without_a_traceback(
    examples: Path, tmp_path: Path
) -> None:
    out = tmp_path / "boom.gif"
    done = softevo(
        "replay",
        str(_blowing_up(examples, tmp_path)),
        "--out",
        str(out),
        "--fps",
        "4",
        "--duration",
        "1",
    )
    assert done.returncode == 0, done.stderr
    with Image.open(out) as image:
        assert image.n_frames == 4


def test_frames_after_the_blow_up_hold_the_last_finite_one() -> None:
    frames = np.zeros((4, 2, 3))
    frames[1] += 1.0
    frames[2, 0, 0] = np.nan
    frames[3] = 1e300  # finite but flung away
    held, at = hold_last_finite(np.array([0.0, 0.5, 1.0, 1.5]), frames)
    assert at == 1.0
    assert (held[2:] == 1.0).all() and (held[:2] == frames[:2]).all()
    assert hold_last_finite(np.arange(2.0), np.zeros((2, 1, 3)))[1] is None
