"""The record of measures a simulation returns (`SimResult.measures`): every number `softevo
simulate` prints that is of the robot, the same values; NaN where not measured; and the docs'
table of measures names each of them (adding one is a line in each place)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

from softevo.core.nulls import from_null_record, record_text
from softevo.core.physics import simulate
from softevo.core.physics.evaluation import evaluate_robot_files
from softevo.core.robots.robot import Actuation, VoxelRobot
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.robots.settings import sim_settings

DOCS = Path(__file__).parents[3] / "docs" / "physics.md"
#: what `softevo simulate` prints that is not a measure: of the machine, of the run, or vectors
NOT_MEASURES = {"wall_seconds", "steps", "com_start", "com_end"}


def crawler() -> VoxelRobot:
    settings = sim_settings({"duration": 1.0, "settle_time": 0.25, "omega": 10.0})
    labels = ("sine", "hard", "neg_sine", "soft", "sine", "hard", "soft", "neg_sine")
    return VoxelRobot((2, 2, 2), labels, Actuation(0.1, 1.0, 0.3), settings)


def test_the_record_holds_every_number_simulate_prints_with_the_same_value() -> None:
    result, _ = simulate(crawler(), energy=True)
    record, printed = result.measures(), result.to_json()
    assert set(printed) - NOT_MEASURES <= set(record)
    for name in set(printed) - NOT_MEASURES:
        assert float(printed[name]) == record[name], name  # stable: 1.0
    assert record["heading"] == result.heading and record["efficiency"] == result.efficiency
    assert all(type(value) is float and math.isfinite(value) for value in record.values())


def test_what_is_not_measured_is_nan_and_the_job_function_sends_it_as_null() -> None:
    result, _ = simulate(crawler(), energy=False)
    record = result.measures()
    assert all(math.isnan(record[name]) for name in ("energy", "cost_of_transport", "efficiency"))
    assert math.isfinite(record["speed"]) and record["stable"] == 1.0
    output = evaluate_robot_files([robot_to_json(crawler()), {"format": "not a robot"}])
    (sent, unbuilt), (text, no_text) = output["measures"], output["texts"]
    assert sent["energy"] is None and sent["speed"] == result.speed  # speed: no energy measured
    assert sent.keys() == record.keys() and unbuilt is None and no_text is None
    # the record's text, as the service stores it: the same as the store would encode from it
    assert json.loads(text) == sent and text == record_text(from_null_record(sent))


def test_the_docs_table_names_every_measure_and_no_other() -> None:
    section = DOCS.read_text().split("## Measures and objectives")[1].split("\n## ")[0]
    rows = [line for line in section.splitlines() if line.startswith("| `")]
    documented = {name for row in rows for name in re.findall(r"`(\w+)`", row.split("|")[1])}
    assert documented == set(simulate(crawler())[0].measures())
