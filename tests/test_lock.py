"""The locks (requirements/dev.txt for CI and the README's test command, requirements/runtime.txt
for the Docker image) and pyproject.toml agree: every declared requirement is locked at a version
inside its declared range, every locked package carries sha256 hashes, the two locks give shared
packages the same version, and CI runs the README's command on the lock. A new release of
anything can then no longer turn CI red by itself (issue 20); `scripts/lock.sh` refreshes them."""

from __future__ import annotations

import os
import re
import tomllib
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


class Locked:
    """One pinned line of a lock: name==version, its marker and its hashes."""

    def __init__(self, text: str) -> None:
        head = text.split(" \\")[0].strip()
        self.requirement = Requirement(head)
        pins = [spec for spec in self.requirement.specifier if spec.operator == "=="]
        assert len(pins) == 1, f"not pinned with ==: {head}"
        self.version = pins[0].version
        self.hashes = re.findall(r"--hash=sha256:([0-9a-f]{64})", text)

    def applies(self) -> bool:
        marker = self.requirement.marker
        return marker is None or marker.evaluate()  # on this interpreter


def read_lock(name: str) -> dict[str, Locked]:
    text = (ROOT / "requirements" / name).read_text()
    entries = re.split(r"\n(?=[A-Za-z0-9])", text)  # a pin starts a line; hashes and comments don't
    locked = [Locked(entry) for entry in entries if re.match(r"[A-Za-z0-9]", entry)]
    return {canonicalize_name(item.requirement.name): item for item in locked}


def declared(*, extras: tuple[str, ...] = ()) -> list[Requirement]:
    project = PYPROJECT["project"]
    lines = list(project["dependencies"])
    for extra in extras:
        lines += project["optional-dependencies"][extra]
    lines += PYPROJECT["build-system"]["requires"]
    return [Requirement(line) for line in lines]


def service_extra() -> list[str]:
    return PYPROJECT["project"]["optional-dependencies"]["service"]


def readme_test_command() -> str:
    readme = (ROOT / "README.md").read_text()
    section = readme.split("Run the checks and the tests", 1)[1]
    return re.search(r"```sh\n(.+?)\n```", section, re.DOTALL).group(1).strip()


@pytest.mark.parametrize(
    ("lock", "extras"),
    [("dev.txt", ("service", "dev")), ("runtime.txt", ("service",))],
    ids=["dev", "runtime"],
)
def test_every_declared_requirement_is_locked_inside_its_range(lock: str, extras: tuple) -> None:
    locked = read_lock(lock)
    for requirement in declared(extras=extras):
        name = canonicalize_name(requirement.name)
        assert name in locked, f"{requirement} is declared but not in requirements/{lock}"
        version = locked[name].version
        assert requirement.specifier.contains(version, prereleases=True), (
            f"requirements/{lock} pins {name}=={version}, outside pyproject's {requirement}"
        )
    # psycopg[binary]: the extra's package is what lets psycopg run without a system libpq
    assert "psycopg-binary" in locked


def test_every_locked_package_has_hashes_and_both_locks_agree() -> None:
    dev, runtime = read_lock("dev.txt"), read_lock("runtime.txt")
    for lock, items in (("dev.txt", dev), ("runtime.txt", runtime)):
        for name, item in items.items():
            assert item.hashes, f"requirements/{lock}: {name} has no sha256 hash"
    assert set(runtime) <= set(dev), f"only in the runtime lock: {set(runtime) - set(dev)}"
    differ = {
        name: (dev[name].version, item.version)
        for name, item in runtime.items()
        if dev[name].version != item.version
    }
    assert not differ, f"the locks pin different versions (dev, runtime): {differ}"
    # what the image needs for the package alone, and no test tool
    assert {"numba", "numpy", "fastapi", "setuptools"} <= set(runtime)
    # the image serves: the service extra is locked whole (pyproject's `service`)
    assert {canonicalize_name(Requirement(line).name) for line in service_extra()} <= set(runtime)
    assert not {"pytest", "schemathesis", "playwright", "ruff"} & set(runtime)


def test_ci_runs_the_readme_test_command_on_the_lock() -> None:
    command = readme_test_command()
    assert command.startswith("pip install -r requirements/dev.txt && "), command
    assert "--no-deps" in command  # the project goes on top of the lock without moving it
    assert command.endswith("&& scripts/lint.sh && python -m pytest"), command
    ci = (ROOT / ".ci" / "run").read_text()
    as_ci = command.replace("pip install", "python -m pip install")
    assert as_ci in ci, "CI does not run the README's test command"


def test_this_run_uses_the_locked_versions() -> None:
    """What the README's test command installed is what is running (under CI, where it must)."""
    wrong = {}
    for name, item in read_lock("dev.txt").items():
        if not item.applies():
            continue
        try:
            installed = metadata.version(name)
        except metadata.PackageNotFoundError:
            installed = "missing"
        if canonicalize_name(installed) != canonicalize_name(item.version):
            wrong[name] = (item.version, installed)
    if wrong and os.environ.get("CI") != "true":
        pytest.skip(f"this environment is not the lock (locked, installed): {wrong}")
    assert not wrong, f"locked vs installed: {wrong}"
