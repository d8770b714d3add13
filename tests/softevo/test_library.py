"""softevo.library, the engine in this process: the same numbers as `softevo run` and
`softevo simulate` (which are built on it) and as core's physics, errors naming the field."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from softevo import library
from softevo.api.app import create_app
from softevo.api.db import Database
from softevo.api.settings import Settings
from softevo.core.config import ConfigError, resolve
from softevo.core.physics import simulate as core_simulate
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.robots.robot_file import RobotFileError, load_robot, with_sim
from tests.api.finished import finished
from tests.softevo.inprocess import softevo

TINY = {"population": 6, "generations": 3, "seed": 4, "sim": {"duration": 1.0}}


def test_evolve_gives_the_curve_and_files_of_softevo_run(tmp_path: Path) -> None:
    out = tmp_path / "run"
    done = softevo(
        "run",
        "--preset",
        "quick",
        "--population",
        "6",
        "--generations",
        "3",
        "--seed",
        "4",
        "--duration",
        "1",
        "--workers",
        "1",
        "--out",
        str(out),
        "--json",
    )
    assert done.returncode == 0, done.stderr
    printed = json.loads(done.stdout)
    result = library.evolve(preset="quick", workers=1, **TINY)
    assert [row["generation"] for row in result.curve] == [0, 1, 2]
    assert result.curve == printed["generations"]
    assert result.config == printed["run"] == json.loads((out / "config.json").read_text())
    assert result.best == json.loads((out / "best_robot.json").read_text())
    assert result.state == json.loads((out / "state.json").read_text())
    assert result.best_fitness == result.curve[-1]["best_so_far"] == printed["best"]["speed"]
    assert (result.evaluations, result.saved) == (printed["evaluations"], printed["saved"])
    assert result.archive is None
    assert {k: v for k, v in result.to_json().items() if k != "wall_seconds"} == {
        k: v for k, v in printed.items() if k not in ("wall_seconds", "out")
    }


def test_evolve_gives_the_curve_and_best_robot_of_the_service(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'softevo.db'}"
    Database(url).upgrade()
    settings = Settings(database_url=url, poll_seconds=0.05, lease_seconds=5.0)
    with TestClient(create_app(settings, lambda _settings: SerialEvaluator())) as client:
        created = client.post("/runs", json={"preset": "quick", **TINY})
        assert created.status_code == 201, created.text
        run_id = created.json()["id"]
        assert finished(client, run_id)["status"] == "completed"
        curve = client.get(f"/runs/{run_id}/curve").json()["generations"]
        best = client.get(f"/runs/{run_id}/best").json()
    result = library.evolve(preset="quick", workers=1, **TINY)
    assert result.curve == curve and result.best == best


def test_the_curve_is_the_same_on_one_worker_and_two() -> None:
    serial = library.evolve({"preset": "quick", **TINY}, workers=1)
    pooled = library.evolve({"preset": "quick", **TINY}, workers=2)
    assert pooled.curve == serial.curve and pooled.best == serial.best


def test_stepping_a_run_gives_the_rows_of_a_whole_one() -> None:
    whole = library.evolve(preset="quick", workers=1, **TINY)
    reported: list[int] = []
    with library.start(resolve({"preset": "quick", **TINY}), workers=1) as run:
        first = run.step()
        rest = list(run)
        assert run.done
        with pytest.raises(RuntimeError, match="all 3 generations ran"):
            run.step()
    assert [first, *rest] == whole.curve
    again = library.start(preset="quick", workers=1, **TINY)
    assert again.finish(lambda update: reported.append(update.stats.generation)) == again.result()
    assert reported == [0, 1, 2] and again.result().curve == whole.curve


def test_overrides_merge_with_the_config_sim_key_by_key() -> None:
    config = library.configure({"preset": "quick", "sim": {"duration": 1.0}}, sim={"dt": 0.0004})
    assert (config.sim.duration, config.sim.dt, config.sim.settle_time) == (1.0, 0.0004, 0.5)
    assert library.configure(config) is config


def test_a_map_elites_run_gives_its_archive(tmp_path: Path) -> None:
    result = library.evolve(
        preset="quick",
        algorithm="map-elites",
        descriptors=["voxels", "actuated"],
        bins=[4, 3],
        workers=1,
        **TINY,
    )
    assert result.archive is not None and result.archive["bins"] == [4, 3]
    filled = len(result.archive["elites"])
    assert filled > 0 and result.curve[-1]["coverage"] == filled / 12
    assert max(e["fitness"] for e in result.archive["elites"]) == result.best_fitness


def test_simulate_is_cores_simulate_of_the_file(examples: Path) -> None:
    path = examples / "crawler_4x4x4.json"
    measures = library.simulate(path, duration=1.5, trajectory_fps=10)
    expected, trajectory = core_simulate(with_sim(load_robot(path), duration=1.5), record_every=200)
    wanted = {**expected.to_json(), "dropped_voxels": 0, "trajectory": trajectory.to_json()}
    assert set(measures) == set(wanted)
    assert {k: measures[k] for k in wanted if k != "wall_seconds"} == {
        k: wanted[k] for k in wanted if k != "wall_seconds"
    }
    assert len(measures["trajectory"]["frames"]) == 16  # 0, 0.1, ..., 1.5 s
    as_dict = library.simulate(json.loads(path.read_text()), duration=1.5)
    assert as_dict["speed"] == measures["speed"] and "trajectory" not in as_dict


def test_bad_input_raises_one_line_naming_the_field(examples: Path, tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"^population: "):
        library.evolve(preset="quick", population=0)
    with pytest.raises(ConfigError, match=r"^preset: unknown preset 'fast'"):
        library.start(preset="fast")
    with pytest.raises(ValueError, match=r"^workers: must be >= 1, got 0"):
        library.start(preset="quick", workers=0)
    with pytest.raises(RobotFileError, match=r"^voxels: "):
        library.simulate({"format": "softevo.robot/1", "shape": [2, 1, 1], "voxels": ["hard"]})
    missing = tmp_path / "missing.json"
    with pytest.raises(RobotFileError, match=rf"^{missing}: cannot read"):
        library.simulate(missing)
    with pytest.raises(RobotFileError, match=r"crawler_4x4x4.json: sim.duration: "):
        library.simulate(examples / "crawler_4x4x4.json", duration=-1.0)
    with pytest.raises(ValueError, match=r"^trajectory_fps: must be a finite number > 0"):
        library.simulate(examples / "crawler_4x4x4.json", trajectory_fps=0.0)


def test_importing_the_library_loads_no_numba() -> None:
    script = (
        "import sys, softevo.library\n"
        "print([m for m in ('numba', 'llvmlite', 'rich', 'matplotlib') if m in sys.modules])"
    )
    done = subprocess.run(
        [sys.executable, "-P", "-c", script], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
