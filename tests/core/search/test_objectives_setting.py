"""The `objectives` run setting (issues 36, 51): names and objects, the reference and ideal
points stored with the run, and one line naming the field for anything wrong."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from softevo.core.config import ConfigError, resolve
from softevo.core.robots.robot_file import RobotFileError, file_energy, parse_robot
from softevo.core.search.vectors import ideal_point, needs_energy, reference_point

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
        {"measure": "speed", "goal": "max", "reference": 0.0, "ideal": 1.0},
        {"measure": "cost_of_transport", "goal": "min", "reference": 100_000.0, "ideal": 0.0},
    ]
    assert resolve(short.to_json()) == short  # what is stored reads back the same
    assert reference_point(short.objectives).tolist() == [0.0, -100_000.0]
    assert ideal_point(short.objectives).tolist() == [1.0, -0.0]
    assert needs_energy(short.objectives) and not needs_energy(resolve({}).objectives)
    own = resolve({"objectives": [{"measure": "heading", "reference": -180}]})
    assert own.objectives[0].reference == -180.0


def test_an_ideal_is_given_or_filled_in_and_a_config_stored_before_ideals_loads() -> None:
    own = resolve({"objectives": [{"measure": "cost_of_transport", "goal": "min", "ideal": 5}]})
    assert own.objectives[0].ideal == 5.0 and own.objectives[0].reference == 100_000.0
    heading = resolve({"objectives": [{"measure": "heading", "reference": -180}]})
    assert heading.objectives[0].ideal == 180.0  # the measure's own, with no default reference
    stored = resolve({"preset": "quick", "objectives": ["speed", "-energy"]}).to_json()
    without = [{k: v for k, v in item.items() if k != "ideal"} for item in stored["objectives"]]
    old = {**stored, "objectives": without}
    assert resolve(old).to_json() == stored  # the defaults fill the ideal in
    past = resolve({**old, "objectives": [{"measure": "speed", "reference": 1.5}]})
    assert past.objectives[0].ideal == 1.5 + 1.0  # a reference past the default ideal loads
    counted = resolve({"objectives": [{"measure": "masses", "goal": "min", "reference": -2}]})
    assert counted.objectives[0].ideal == -3.0  # one unit past it: no default range
    huge = resolve({"objectives": [{"measure": "speed", "reference": 1e300}]}).objectives[0]
    assert huge.ideal == math.nextafter(1e300, math.inf)  # the next number: still better
    with pytest.raises(ConfigError, match=r"^objectives: item 0: no ideal is better than"):
        resolve({"objectives": [{"measure": "speed", "reference": 1.7976931348623157e308}]})


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
        ([{"measure": "speed", "ideal": "1"}], "objectives: item 0: ideal must be a number"),
        ([{"measure": "speed", "ideal": math.inf}], "objectives: item 0: ideal must be finite"),
        (
            ["speed", {"measure": "energy", "goal": "min", "ideal": 2e6}],
            "objectives: item 1: ideal must be better than the reference (below 1e+06)",
        ),
        (
            [{"measure": "speed", "reference": 0.2, "ideal": 0.2}],
            "objectives: item 0: ideal must be better than the reference (above 0.2)",
        ),
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
