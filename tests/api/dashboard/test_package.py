"""The dashboard's files ship in the package (pyproject package-data), so `pip install .`
serves the same page offline as an editable checkout; and what a wheel installs lives under
`softevo` only, so a user's own `core` or `api` package and softevo never shadow each other."""

from __future__ import annotations

import fnmatch
import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]


def test_every_static_file_is_package_data() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    patterns = config["tool"]["setuptools"]["package-data"]["softevo.api.dashboard"]
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


def test_every_package_folder_is_listed_for_the_install() -> None:
    """pyproject maps the top-level folders under `softevo`, so its package list is explicit:
    every folder with an __init__.py must be on it (or the install silently lacks it)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    folders = {
        installed_name(init.parent / "x.py").removesuffix("/x.py").replace("/", ".")
        for top in ("core", "api", "worker", "softevo", "migrations")
        for init in (ROOT / top).rglob("__init__.py")
    }
    data_only = {"softevo.docs"}  # docs/*.md, the guides `softevo docs` shows: no __init__.py
    assert folders | data_only == set(config["packages"])


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


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """`pip wheel .` (what `pip install .` builds), on the locked setuptools (no isolation)."""
    tmp_path = tmp_path_factory.mktemp("wheel")
    source = tmp_path / "source"  # a copy: setuptools writes build/ into the tree it builds
    skip = shutil.ignore_patterns(".git", "build", "*.egg-info", "__pycache__", "test-artifacts")
    shutil.copytree(ROOT, source, ignore=skip)
    built = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "-q",
            "--no-deps",
            "--no-build-isolation",
            str(source),
            "-w",
            str(tmp_path),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert built.returncode == 0, built.stdout + built.stderr
    (built_wheel,) = tmp_path.glob("softevo-*.whl")
    return built_wheel


def installed_name(path: Path) -> str:
    """Where a file of the repository lands in the wheel (pyproject's package-dir)."""
    relative = path.relative_to(ROOT).as_posix()
    return relative if relative.startswith("softevo/") else f"softevo/{relative}"


@pytest.mark.slow
def test_a_built_wheel_ships_every_dashboard_file_and_the_migrations(wheel: Path) -> None:
    """The real thing, not the glob rules: the files inside the wheel. Without them a
    non-editable install serves a page with no scripts."""
    names = set(zipfile.ZipFile(wheel).namelist())
    static = ROOT / "api" / "dashboard" / "static"
    wanted = {installed_name(p) for p in static.rglob("*") if p.is_file()}
    assert len(wanted) >= 10 and wanted - names == set()
    migrations = ROOT / "migrations"
    wanted = {
        installed_name(p)
        for p in migrations.rglob("*")
        if p.is_file() and p.suffix in (".py", ".mako")
    }
    assert wanted - names == set()
    for folder in ("core", "api", "worker", "softevo"):  # every module of every package
        wanted = {installed_name(p) for p in (ROOT / folder).rglob("*.py")}
        assert wanted - names == set(), f"{folder}/ modules missing from the wheel"


@pytest.mark.slow
def test_a_wheel_installs_nothing_but_softevo_and_shadows_no_users_package(
    wheel: Path, tmp_path: Path
) -> None:
    top = {name.split("/")[0] for name in zipfile.ZipFile(wheel).namelist()}
    assert top == {"softevo", f"{wheel.name.split('-')[0]}-{wheel.name.split('-')[1]}.dist-info"}
    target, project = tmp_path / "site", tmp_path / "project"
    installed = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "-q",
            "--no-deps",
            "--target",
            str(target),
            str(wheel),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert installed.returncode == 0, installed.stdout + installed.stderr
    for name in ("core", "api"):  # a user's project with packages of these generic names
        (project / name).mkdir(parents=True)
        (project / name / "__init__.py").write_text(f"MINE = {name!r}\n")
    check = (
        "import core, api, softevo.core.physics, softevo.api.app, softevo.cli;"
        "print(core.MINE, api.MINE, softevo.core.physics.__file__)"
    )
    done = subprocess.run(
        [sys.executable, "-c", check],
        cwd=project,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "PYTHONPATH": f"{project}{os.pathsep}{target}"},
    )
    assert done.returncode == 0, done.stderr
    mine_core, mine_api, physics = done.stdout.split()
    assert (mine_core, mine_api) == ("core", "api")
    assert Path(physics).is_relative_to(target)
