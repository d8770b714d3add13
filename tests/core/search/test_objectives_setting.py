"""The `objectives` run setting (issue 36): names and objects, the reference point stored with
the run, and one line naming the field for anything wrong."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from softevo.core.config import ConfigError, resolve
from softevo.core.robots.robot_file import RobotFileError, file_energy, parse_robot
from softevo.core.search.vectors import needs_energy, reference_point

EXAMPLES = Path(__file__).parents[3] / "docs" / "experiments"


def test_names_and_objects_are_one_setting_stored_with_their_reference() -> None:
    short = resolve({"preset": "quick", "objectives": ["speed", "-cost_of_transport"]})
    long = resolve(
        {
            "preset": "quick",
            "objectives": [{"measure": "speed"}, {"measure": "cost_of_transport", "goal": "min"}],
        }
    )
    assert short == long
    stored = short.to_json()["objectives"]
    assert stored == [
        {"measure": "speed", "goal": "max", "reference": 0.0},
        {"measure": "cost_of_transport", "goal": "min", "reference": 100_000.0},
    ]
    assert resolve(short.to_json()) == short  # what is stored reads back the same
    assert reference_point(short.objectives).tolist() == [0.0, -100_000.0]
    assert needs_energy(short.objectives) and not needs_energy(resolve({}).objectives)
    own = resolve({"objectives": [{"measure": "heading", "reference": -180}]})
    assert own.objectives[0].reference == -180.0


def test_a_run_without_objectives_keeps_its_stored_config() -> None:
    assert "objectives" not in resolve({"preset": "quick"}).to_json()


@pytest.mark.parametrize(
    ("objectives", "message"),
    [
        (["sped"], "objectives: item 0: unknown measure 'sped'"),
        ("speed", "objectives: a list of measure names or objects"),
        (["speed", "speed"], "objectives: each measure at most once"),
        ([{"measure": "speed", "goal": "up"}], "objectives: item 0: goal must be 'max' or 'min'"),
        ([{"measure": "speed", "weight": 2}], "objectives: item 0: unknown key 'weight'"),
        (["speed", {"measure": "heading"}], "objectives: item 1: heading has no default"),
        ([{"measure": "speed", "reference": "0"}], "objectives: item 0: reference must be a"),
        (["speed", "distance", "energy", "climb_rate", "springs"], "objectives: at most 4"),
    ],
)
def test_bad_objectives_are_named_in_one_line(objectives: object, message: str) -> None:
    with pytest.raises(ConfigError) as caught:
        resolve({"objectives": objectives})
    assert str(caught.value).startswith(message) and "\n" not in str(caught.value)


def test_a_robot_file_may_ask_for_the_actuators_work() -> None:
    document = json.loads((EXAMPLES / "best_4x4x4.json").read_text())
    assert not file_energy(document)
    parse_robot({**document, "energy": True})
    assert file_energy({**document, "energy": True})
    with pytest.raises(RobotFileError, match=r"^energy: Input should be a valid boolean$"):
        parse_robot({**document, "energy": "yes"})
