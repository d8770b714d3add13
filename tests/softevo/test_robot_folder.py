"""`softevo simulate|export|replay DIR`: a `softevo run` results folder stands for its best
robot (best_robot.json); a folder without one is refused in one line, never a traceback."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from softevo.core.robots.robot_file import RESULTS_ROBOT, RobotFileError, load_robot, robot_to_json
from tests.softevo.inprocess import softevo


@pytest.fixture
def results(examples: Path, tmp_path: Path) -> Path:
    folder = tmp_path / "results"
    folder.mkdir()
    shutil.copy(examples / "crawler_4x4x4.json", folder / RESULTS_ROBOT)
    return folder


def test_a_results_folder_is_its_best_robot(examples: Path, results: Path) -> None:
    from_folder, from_file = load_robot(results), load_robot(examples / "crawler_4x4x4.json")
    assert robot_to_json(from_folder) == robot_to_json(from_file)


def test_export_of_a_results_folder_writes_its_best_robot(results: Path, tmp_path: Path) -> None:
    out = tmp_path / "best.stl"
    done = softevo("export", str(results), "--out", str(out))
    assert done.returncode == 0, done.stderr
    assert out.stat().st_size > 0


@pytest.mark.parametrize(
    "command",
    [("simulate",), ("export", "--out", "x.stl"), ("replay", "--out", "x.gif")],
)
def test_a_folder_without_a_robot_is_refused_in_one_line(
    tmp_path: Path, command: tuple[str, ...]
) -> None:
    empty = tmp_path / "empty"
    empty.mkdir()
    done = softevo(command[0], str(empty), *command[1:], cwd=tmp_path)
    assert done.returncode == 1
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and RESULTS_ROBOT in lines[0], done.stderr
    with pytest.raises(RobotFileError, match=RESULTS_ROBOT):
        load_robot(empty)
