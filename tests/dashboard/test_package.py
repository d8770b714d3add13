"""The dashboard's files ship in the package (pyproject package-data), so `pip install .`
serves the same page offline as an editable checkout."""

from __future__ import annotations

import fnmatch
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_every_static_file_is_package_data() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    patterns = config["tool"]["setuptools"]["package-data"]["api.dashboard"]
    folder = ROOT / "api" / "dashboard"
    files = [
        p.relative_to(folder).as_posix() for p in (folder / "static").rglob("*") if p.is_file()
    ]
    assert len(files) >= 10
    # setuptools globs do not cross "/": a pattern must match the whole relative path
    unshipped = [
        f
        for f in files
        if not any(fnmatch.fnmatch(f, p) and f.count("/") == p.count("/") for p in patterns)
    ]
    assert unshipped == []


def test_vendored_libraries_carry_their_licences() -> None:
    vendor = ROOT / "api" / "dashboard" / "static" / "vendor"
    for library in ("uplot", "three"):
        assert (
            "MIT" in (vendor / library / "LICENSE").read_text()[:200]
            or "MIT" in (vendor / library / "LICENSE").read_text()
        )
    sums = (vendor / "SHA256SUMS").read_text().splitlines()
    assert {line.split()[1] for line in sums} >= {
        "./uplot/uPlot.iife.min.js",
        "./three/three.module.js",
    }


@pytest.mark.slow
def test_a_built_wheel_ships_every_dashboard_file_and_the_migrations(tmp_path: Path) -> None:
    """The real thing, not the glob rules: `pip wheel .` (what `pip install .` builds) and the
    files inside it. Without them a non-editable install serves a page with no scripts."""
    source = tmp_path / "source"  # a copy: setuptools writes build/ into the tree it builds
    skip = shutil.ignore_patterns(".git", "build", "*.egg-info", "__pycache__", "test-artifacts")
    shutil.copytree(ROOT, source, ignore=skip)
    built = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", str(source), "-w", str(tmp_path)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert built.returncode == 0, built.stdout + built.stderr
    (wheel,) = tmp_path.glob("softevo-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    static = ROOT / "api" / "dashboard" / "static"
    wanted = {p.relative_to(ROOT).as_posix() for p in static.rglob("*") if p.is_file()}
    assert len(wanted) >= 10 and wanted - names == set()
    migrations = ROOT / "migrations"
    wanted = {
        p.relative_to(ROOT).as_posix()
        for p in migrations.rglob("*")
        if p.is_file() and p.suffix in (".py", ".mako")
    }
    assert wanted - names == set()
