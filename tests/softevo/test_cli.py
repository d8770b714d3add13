"""The `softevo` command as a user runs it: `main(argv)` in process, real files, output parsed."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from softevo.core.robots.robot_file import load_robot
from tests.softevo.inprocess import softevo


def test_help_lists_simulate() -> None:
    done = softevo("--help")
    assert done.returncode == 0
    assert "simulate" in done.stdout
    assert softevo("simulate", "--help").returncode == 0


def test_simulate_prints_result_and_writes_trajectory(examples: Path, tmp_path: Path) -> None:
    trajectory_path = tmp_path / "trajectory.json"
    done = softevo(
        "simulate",
        str(examples / "paper_cube.json"),
        "--duration",
        "2",
        "--trajectory",
        str(trajectory_path),
        "--fps",
        "10",
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert set(result) >= {
        "masses",
        "springs",
        "steps",
        "com_start",
        "com_end",
        "distance",
        "speed",
        "wall_seconds",
    }
    assert (result["masses"], result["springs"], result["steps"]) == (8, 28, 4000)
    settle = load_robot(examples / "paper_cube.json").sim.settle_time
    assert result["speed"] == pytest.approx(result["distance"] / (2.0 - settle))
    trajectory = json.loads(trajectory_path.read_text())
    assert trajectory["format"] == "softevo.trajectory/1"
    assert len(trajectory["frames"]) == len(trajectory["times"]) == 21  # 0, 0.1, ..., 2.0 s
    assert len(trajectory["frames"][0]) == 8 and len(trajectory["springs"]) == 28
    assert trajectory["times"][-1] == pytest.approx(2.0)


def test_example_crawler_crawls(examples: Path) -> None:
    done = softevo("simulate", str(examples / "crawler_4x4x4.json"))
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["speed"] > 0.01


@pytest.mark.parametrize(
    ("content", "words"),
    [
        ('{"format": "softevo.robot/1", "shape": [1, 1, 1], "voxels": ["jelly"]}', "voxels.0"),
        ("{oops", "not valid JSON"),
        (
            '{"format": "softevo.robot/1", "shape": [1, 1, 1], "voxels": ["hard"],'
            ' "sim": {"dt": -1}}',
            "sim.dt",
        ),
        # actuated voxels without their genes would run as a = b = c = 0, a still robot
        (
            '{"format": "softevo.robot/1", "shape": [2, 1, 1], "voxels": ["sine", "hard"]}',
            "actuation: required: voxels has 1 sine",
        ),
    ],
)
def test_bad_file_exits_nonzero_with_one_line(tmp_path: Path, content: str, words: str) -> None:
    path = tmp_path / "bad.json"
    path.write_text(content)
    done = softevo("simulate", str(path))
    assert done.returncode == 1
    assert done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith(f"softevo simulate: error: {path}: ")
    assert words in lines[0]


def test_bad_arguments_exit_nonzero(examples: Path, tmp_path: Path) -> None:
    done = softevo("simulate", str(examples / "paper_cube.json"), "--duration", "-1")
    assert done.returncode == 2 and "--duration" in done.stderr
    done = softevo("simulate", str(tmp_path / "missing.json"))
    assert done.returncode == 1 and "cannot read" in done.stderr
    assert softevo("fly").returncode == 2


HOSTILE = {
    "deep": "[" * 100_000 + "]" * 100_000,
    "huge": '{"voxels": ["' + "hard" * 3_000_000 + '"]}',
    "nan": '{"format": "softevo.robot/1", "shape": [1, 1, 1], "voxels": ["hard"],'
    ' "sim": {"duration": NaN}}',
    "nested label": '{"format": "softevo.robot/1", "shape": [1, 1, 1], "voxels": [["hard"]]}',
    "shape string": '{"format": "softevo.robot/1", "shape": "1x1x1", "voxels": ["hard"]}',
}


@pytest.mark.parametrize(
    ("name", "words"),
    [
        ("deep", "nested too deeply"),
        ("huge", "more than the limit"),
        ("nan", "NaN"),
        ("nested label", "voxels.0"),
        ("shape string", "shape"),
    ],
)
def test_hostile_robot_files_are_refused_in_one_line(tmp_path: Path, name: str, words: str) -> None:
    path = tmp_path / "hostile.json"
    path.write_text(HOSTILE[name])
    done = softevo("simulate", str(path))
    assert done.returncode == 1 and done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and len(lines[0]) < 500, done.stderr[:1000]
    assert words in lines[0], lines[0]


def test_simulate_says_how_many_cut_off_voxels_it_dropped(tmp_path: Path) -> None:
    # a 4x1x1 bar with its second voxel empty: the first voxel is cut off from the other two
    path = tmp_path / "apart.json"
    path.write_text(
        '{"format": "softevo.robot/1", "shape": [4, 1, 1], "voxels": ["hard", "empty", "hard",'
        ' "hard"], "sim": {"duration": 0.3, "settle_time": 0.1}}'
    )
    done = softevo("simulate", str(path))
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["dropped_voxels"] == 1
    assert result["masses"] == 12  # the two joined voxels alone
    assert "1 filled voxel(s) not face-connected" in done.stderr


def test_simulate_into_a_closed_pipe_exits_quietly(examples: Path) -> None:
    process = subprocess.Popen(
        [
            sys.executable,
            "-P",
            "-m",
            "softevo.cli",
            "simulate",
            str(examples / "paper_cube.json"),
            "--duration",
            "1.5",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert process.stdout is not None and process.stderr is not None
    process.stdout.close()  # what `| head` does once it has its lines: the reader goes away
    stderr = process.stderr.read().decode()
    assert process.wait(timeout=120) == 141
    assert stderr == "", stderr  # no BrokenPipeError traceback


def test_serve_on_a_taken_port_fails_in_one_line_before_starting(tmp_path: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = softevo("serve", "--port", str(port), "--migrate", cwd=tmp_path)
    assert done.returncode == 1
    assert (
        done.stderr == f"softevo serve: error: cannot listen on 127.0.0.1:{port} "
        "(Address already in use)\n"
    )
    assert not (tmp_path / "softevo.db").exists()  # nothing migrated, nothing started
