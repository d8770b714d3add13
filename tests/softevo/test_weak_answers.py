"""Small mistakes get one line naming what is wrong, before any work is done (issue 48): another
of softevo's files given as a robot file, --fps and --duration out of range, --out in a folder
that is not there or naming a folder."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from softevo.core.config import resolve
from softevo.core.outputs import picture
from softevo.core.robots.robot_file import dump_robot, load_robot
from tests.softevo.inprocess import Done, softevo


def _never(*args: object, **kwargs: object) -> None:
    raise AssertionError("the command did work before saying what was wrong")


@pytest.fixture
def no_work(monkeypatch: pytest.MonkeyPatch) -> None:
    """Simulating, drawing or exporting fails the test: the error must come first."""
    from softevo.core.outputs import export
    from softevo.core.physics import evaluation

    monkeypatch.setattr(evaluation, "warm_up", _never)
    monkeypatch.setattr(picture, "movie", _never)
    monkeypatch.setattr(export, "export_robot", _never)


@pytest.fixture
def run_folder(tmp_path: Path, examples: Path) -> Path:
    """What a `softevo run` folder holds, as far as these commands read it."""
    folder = tmp_path / "run"
    folder.mkdir()
    config = resolve({"preset": "quick", "seed": 1}).to_json()
    (folder / "config.json").write_text(json.dumps(config))
    (folder / "curve.json").write_text(json.dumps({"run": config, "generations": []}))
    dump_robot(load_robot(examples / "crawler_4x4x4.json"), folder / "best_robot.json")
    return folder


def _one_line(done: Done, command: str) -> str:
    assert done.returncode == 1, done.stderr
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert done.stderr.startswith(f"softevo {command}: error: ")
    return done.stderr


@pytest.mark.parametrize("command", ["simulate", "export", "replay"])
def test_a_run_config_is_named_as_one(command: str, run_folder: Path, no_work: None) -> None:
    given = run_folder / "config.json"
    out = ["--out", str(run_folder / "x.glb" if command == "export" else run_folder / "x.gif")]
    said = _one_line(softevo(command, str(given), *(out if command != "simulate" else [])), command)
    assert f"{given}: a run config, not a robot file (softevo.robot/1)" in said
    assert f"the run's robot is {run_folder / 'best_robot.json'}" in said


def test_other_json_is_named_in_one_line(run_folder: Path, tmp_path: Path, no_work: None) -> None:
    said = _one_line(softevo("simulate", str(run_folder / "curve.json")), "simulate")
    assert "a run's learning curve (curve.json), not a robot file" in said
    request = tmp_path / "request.json"  # a POST /runs body, away from any run folder
    request.write_text(json.dumps({"preset": "quick", "seed": 1, "shape": [3, 3, 3]}))
    said = _one_line(softevo("simulate", str(request)), "simulate")
    assert "a run config, not a robot file" in said and "give a robot file" in said
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"name": "x", "value": 1}))
    said = _one_line(softevo("simulate", str(other)), "simulate")
    assert "fields no robot file has (name, value), not a robot file" in said
    trajectory = tmp_path / "trajectory.json"
    trajectory.write_text(json.dumps({"format": "softevo.trajectory/1", "frames": []}))
    assert "a trajectory" in _one_line(softevo("simulate", str(trajectory)), "simulate")


def test_a_robot_file_with_a_mistake_is_still_told_its_field(tmp_path: Path) -> None:
    robot = tmp_path / "robot.json"
    robot.write_text(json.dumps({"shape": [1, 1, 1], "voxels": ["soft"]}))
    assert "format: Field required" in _one_line(softevo("simulate", str(robot)), "simulate")
    robot.write_text(json.dumps({"format": "softevo.robot/1", "shape": [1, 1, 1], "x": 1}))
    said = _one_line(softevo("simulate", str(robot)), "simulate")
    assert "x: Extra inputs are not permitted" in said and "not a robot file" not in said


@pytest.mark.parametrize(
    ("option", "value", "said"),
    [
        ("--fps", "100", "--fps must be between"),
        ("--fps", "0.1", "--fps must be between"),
        ("--duration", "999", "--duration must be at most"),
    ],
)
def test_replay_options_out_of_range_blame_the_option(
    examples: Path, tmp_path: Path, no_work: None, option: str, value: str, said: str
) -> None:
    robot = str(examples / "crawler_4x4x4.json")
    done = softevo("replay", robot, "--out", str(tmp_path / "a.gif"), option, value)
    assert done.returncode == 2 and said in done.stderr, done.stderr
    assert robot not in done.stderr and done.stderr.count("\n") == 1


def test_replay_into_a_missing_folder_fails_before_simulating(
    examples: Path, tmp_path: Path, no_work: None
) -> None:
    out = tmp_path / "missing" / "x.gif"
    said = _one_line(
        softevo("replay", str(examples / "crawler_4x4x4.json"), "--out", str(out)), "replay"
    )
    assert f"{out}: cannot write (no folder {out.parent})" in said


def test_simulate_checks_its_trajectory_file_first(
    examples: Path, tmp_path: Path, no_work: None
) -> None:
    out = tmp_path / "missing" / "t.json"
    done = softevo("simulate", str(examples / "crawler_4x4x4.json"), "--trajectory", str(out))
    assert f"{out}: cannot write (no folder" in _one_line(done, "simulate")


@pytest.mark.parametrize(("command", "example"), [("export", "robot.glb"), ("replay", "robot.gif")])
def test_out_naming_a_folder_says_it_wants_a_file(
    command: str, example: str, examples: Path, tmp_path: Path, no_work: None
) -> None:
    done = softevo(command, str(examples / "crawler_4x4x4.json"), "--out", str(tmp_path))
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert f"--out {tmp_path} is a folder: give the file to write, e.g. {tmp_path / example}" in (
        done.stderr
    )
    assert "--format is needed" not in done.stderr


PARETO = ["speed", "-cost_of_transport"]


@pytest.mark.parametrize(
    ("request_", "noted"),
    [
        ({"objectives": PARETO}, ["objectives"]),
        ({"algorithm": "random", "objectives": PARETO, "descriptors": ["voxels"]}, ["both"]),
        ({"algorithm": "hillclimb", "descriptors": ["voxels"]}, ["descriptors"]),
        ({"preset": "map-elites", "algorithm": "ga"}, ["descriptors"]),
        ({"algorithm": "nsga2", "objectives": PARETO}, []),
        ({"algorithm": "afpo", "objectives": PARETO}, []),
        ({"objectives": PARETO, "options": {"weights": [1, 0]}}, []),
        ({"algorithm": "map-elites", "descriptors": ["voxels"]}, []),
        (
            {
                "algorithm": "steady-state",
                "descriptors": ["voxels"],
                "options": {"parents": "archive"},
            },
            [],
        ),
        ({}, []),
    ],
)
def test_settings_the_algorithm_does_not_breed_on_are_noted(
    request_: dict, noted: list[str]
) -> None:
    """Objectives and descriptors an algorithm does not select on only fill the front and the
    archive kept beside it (how random search and the GA are compared on them): said, not
    refused, and never for the algorithms that read them."""
    from softevo.run_config import breeding_notes

    notes = breeding_notes(resolve({"preset": "quick", **request_}))
    kinds = ["objectives" if "--objectives" in n else "descriptors" for n in notes]
    assert kinds == (["objectives", "descriptors"] if noted == ["both"] else noted), notes


def test_softevo_run_says_the_note_in_one_line_and_runs(tmp_path: Path) -> None:
    out = str(tmp_path / "run")
    small = ["--population", "4", "--generations", "1", "--duration", "1", "--workers", "1"]
    pareto = ["--objectives", "speed,-cost_of_transport"]
    done = softevo("run", "--preset", "quick", *small, *pareto, "--out", out, "--json")
    assert done.returncode == 0, done.stderr
    notes = [line for line in done.stderr.splitlines() if line.startswith("softevo run: note: ")]
    assert len(notes) == 1 and "ga selects on the fitness (speed) alone" in notes[0]
    assert "nsga2 and afpo select on them" in notes[0]
    assert (tmp_path / "run" / "front.csv").is_file()  # the front beside the GA, as said


def test_folder_names_say_what_ran_and_the_hash_still_parts_configs() -> None:
    from softevo.run_config import config_hash, default_out

    def name(**request: object) -> str:
        config = resolve({"preset": "quick", "seed": 1, **request})
        folder = default_out(config)
        assert folder.parent == Path("softevo-runs")
        assert folder.name.endswith(f"-seed1-{config_hash(config)}")
        return folder.name.rsplit("-seed", 1)[0]

    assert name() == "quick-3x3x3-ga-voxel"
    assert name(algorithm="nsga2", objectives=PARETO) == (
        "quick-3x3x3-nsga2-voxel-speed+min_cost_of_transport"
    )
    assert name(encoding="cppn", shape=[4, 4, 4]) == "quick-4x4x4-ga-cppn"
    assert name(sim={"terrain": {"kind": "rough"}}, objective="forward") == (
        "quick-3x3x3-ga-voxel-rough-forward"
    )
    task = default_out(resolve({"preset": "task-slope", "seed": 1})).name
    assert task.startswith("task-slope-4x4x4-ga-voxel-seed1-")  # the preset's terrain: unsaid
    one = default_out(resolve({"preset": "quick", "population": 6}))
    other = default_out(resolve({"preset": "quick", "population": 8}))
    assert one.name.rsplit("-", 1)[0] == other.name.rsplit("-", 1)[0] and one != other
