"""softevo as `pip install .` leaves it (`tests/softevo/installed.py`), run from a folder that is
not the repository. (Its `softevo reproduce --quick` is the run `test_reproduce.py` checks.)"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.softevo.installed import ROOT, clean_env, install_wheel


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return install_wheel(tmp_path_factory.mktemp("installed"))


@pytest.mark.slow
def test_the_wheel_is_what_runs_and_carries_the_guides(installed: Path, tmp_path: Path) -> None:
    where = subprocess.run(
        [str(installed / "bin" / "python"), "-c", "import softevo; print(softevo.__file__)"],
        check=True,
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=clean_env(),
    ).stdout.strip()
    assert where.startswith(str(installed)), where  # the wheel's softevo, not the checkout's
    guide = subprocess.run(
        [str(installed / "bin" / "softevo"), "docs", "tasks"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=clean_env(),
        timeout=60,
    )
    assert guide.returncode == 0 and guide.stdout.startswith("# Tasks"), guide.stderr


def test_the_shipped_breathing_cube_is_the_example() -> None:
    shipped = ROOT / "softevo" / "reproduce" / "data" / "breathing_cube.json"
    example = ROOT / "examples" / "breathing_cube.json"
    assert json.loads(shipped.read_text()) == json.loads(example.read_text())
