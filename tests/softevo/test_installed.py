"""softevo as `pip install .` leaves it: a wheel in a fresh virtual environment, run from a folder
that is not the repository, so nothing can be read from the checkout (issue 19: `softevo
reproduce` read examples/ next to the source and crashed once installed)."""

from __future__ import annotations

import json
import os
import shutil
import site
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
#: What pyproject.toml builds the wheel from.
PACKAGED = ("pyproject.toml", "README.md", "softevo", "core", "api", "worker", "migrations", "docs")


def _clean_env() -> dict[str, str]:
    """The environment without anything that would put the checkout on the path."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A venv holding the built wheel; its dependencies come from this venv's site-packages
    through a .pth line (added after its own site-packages, so its softevo comes first)."""
    work = tmp_path_factory.mktemp("installed")
    source = work / "source"  # a copy: building in the checkout would leave a build/ whose
    # stale files (of modules since deleted) would go into later wheels
    source.mkdir()
    for name in PACKAGED:
        if (ROOT / name).is_dir():
            ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
            shutil.copytree(ROOT / name, source / name, ignore=ignore)
        else:
            shutil.copy2(ROOT / name, source / name)
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", str(work / "dist"), str(source)],
        check=True, capture_output=True, timeout=300,
    )  # fmt: skip
    (wheel,) = (work / "dist").glob("softevo-*.whl")
    venv = work / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    purelib = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        check=True, capture_output=True, text=True,
    ).stdout.strip()  # fmt: skip
    Path(purelib, "dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    subprocess.run(
        [sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps",
         "--no-index", "-q", str(wheel)],
        check=True, capture_output=True, timeout=300, env=_clean_env(),
    )  # fmt: skip
    return venv


@pytest.mark.slow
def test_the_wheel_carries_what_reproduce_reads(installed: Path, tmp_path: Path) -> None:
    where = subprocess.run(
        [str(installed / "bin" / "python"), "-c", "import softevo; print(softevo.__file__)"],
        check=True, capture_output=True, text=True, cwd=tmp_path, env=_clean_env(),
    ).stdout.strip()  # fmt: skip
    assert where.startswith(str(installed)), where  # the wheel's softevo, not the checkout's
    out = tmp_path / "out"
    done = subprocess.run(
        [str(installed / "bin" / "softevo"), "reproduce", "--quick", "--workers", "1", "--out",
         str(out)],
        capture_output=True, text=True, cwd=tmp_path, env=_clean_env(), timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    assert (out / "phase1_breathing_cube.png").read_bytes()[:4] == b"\x89PNG"
    assert "Phase 1" in (out / "results.md").read_text()
    guide = subprocess.run(
        [str(installed / "bin" / "softevo"), "docs", "tasks"],
        capture_output=True, text=True, cwd=tmp_path, env=_clean_env(), timeout=60,
    )  # fmt: skip
    assert guide.returncode == 0 and guide.stdout.startswith("# Tasks"), guide.stderr


def test_the_shipped_breathing_cube_is_the_example() -> None:
    shipped = ROOT / "softevo" / "reproduce" / "data" / "breathing_cube.json"
    example = ROOT / "examples" / "breathing_cube.json"
    assert json.loads(shipped.read_text()) == json.loads(example.read_text())
