"""The dashboard's measures with their units (api/dashboard/static/units.js), run by node: an
energy of 32113.0923 J reads 32.11 kJ, and the cost of transport says its unit (issue 39)."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

DASH = "\u2013"  # what the dashboard shows for a missing number
UNITS = Path(__file__).resolve().parents[3] / "api" / "dashboard" / "static" / "units.js"


def test_energy_and_cost_of_transport_read_with_units() -> None:
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed")
    script = (
        f"import {{ energyText, costOfTransportText, significant }} from '{UNITS.as_uri()}';"
        "console.log(JSON.stringify([energyText(32113.0923), energyText(12.345678), "
        "energyText(2.5e6), energyText(null), costOfTransportText(12.3456), "
        "costOfTransportText(null), significant(0.000123456)]));"
    )
    done = subprocess.run(
        [node, "--input-type=module", "-e", script], capture_output=True, text=True, timeout=30
    )
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == [
        "32.11 kJ",
        "12.35 J",
        "2.5 MJ",
        DASH,
        "12.35 J/(N·m) (dimensionless)",
        DASH,
        "0.0001235",
    ]


def run_node(script: str) -> object:
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed")
    done = subprocess.run(
        [node, "--input-type=module", "-e", script], capture_output=True, text=True, timeout=30
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_objectives_read_with_units_and_an_outlier_does_not_squash_the_front() -> None:
    """Issue 48: cost of transport is dimensionless (never "1"); an axis where one robot at 8000
    would flatten a front below 400 is logarithmic, a signed one clipped; ticks are round."""
    script = (
        f"import * as u from '{UNITS.as_uri()}';"
        "const costs = [...Array(40).keys()].map((i) => 20 + 10 * i).concat([8000]);"
        "console.log(JSON.stringify([u.measureLabel('cost_of_transport'), u.measureLabel('speed'),"
        "u.objectiveShort({measure: 'cost_of_transport', goal: 'min'}),"
        "u.hypervolumeUnit([{measure: 'speed'}, {measure: 'cost_of_transport'}]),"
        "u.axisScale(costs, [20, 60, 300]).kind, u.axisScale(costs.slice(0, 40), [20, 300]).kind,"
        "u.axisScale([-0.1, 0, 0.05, 0.1, -40], [0.1]).kind,"
        "u.ticks({kind: 'linear', lo: 0, hi: 0.23}), u.ticks({kind: 'log', lo: 2, hi: 8000}),"
        "u.significant(22430.4)]));"
    )
    assert run_node(script) == [
        "cost of transport (dimensionless)",
        "speed (m/s)",
        "cost of transport ↓",
        "m/s",
        "log",
        "linear",
        "clipped",
        [0, 0.05, 0.1, 0.15, 0.2],
        [10, 100, 1000],
        "22430",
    ]
