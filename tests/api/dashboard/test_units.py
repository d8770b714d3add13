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
        "32.11 kJ", "12.35 J", "2.5 MJ", DASH, "12.35 J/(N·m) (dimensionless)", DASH, "0.0001235",
    ]  # fmt: skip
