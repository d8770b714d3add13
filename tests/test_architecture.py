"""The boundary the user asked for: `core` (installed as `softevo.core`) imports none of the
service's packages, `worker` does not import the API. Checked on every import statement of the
source, so it fails as soon as one is added."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SERVICE = ("sqlalchemy", "redis", "rq", "fastapi", "alembic", "uvicorn")
# folder -> what it may import of softevo, and the outside packages it must not import
ALLOWED_OWN = {"core": ("softevo.core",), "worker": ("softevo.core", "softevo.worker")}
FORBIDDEN = {"core": set(SERVICE), "worker": {"fastapi", "sqlalchemy", "alembic", "uvicorn"}}


def imported_modules(path: Path) -> set[str]:
    """Dotted names of every module imported anywhere in a file (also inside functions)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
            if node.module == "softevo":  # `from softevo import api` imports softevo.api
                names.update(f"softevo.{alias.name}" for alias in node.names)
    return names


def offends(package: str, name: str) -> bool:
    own = name == "softevo" or name.startswith("softevo.")
    if own:
        return name != "softevo" and not name.startswith(ALLOWED_OWN[package])
    return name.split(".")[0] in FORBIDDEN[package]


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_does_not_import_forbidden_modules(package: str) -> None:
    files = sorted((ROOT / package).rglob("*.py"))
    assert files, f"no source files found in {package}/"
    offenders = {
        f"{path.relative_to(ROOT)} imports {name}"
        for path in files
        for name in imported_modules(path)
        if offends(package, name)
    }
    assert not offenders, sorted(offenders)


def test_checker_catches_a_forbidden_import(tmp_path: Path) -> None:
    source = tmp_path / "bad.py"
    source.write_text(
        "def f():\n    from sqlalchemy import select\n    import redis.client\n"
        "    from softevo import api\n    from softevo.core import physics\n"
    )
    names = imported_modules(source)
    assert {name for name in names if offends("core", name)} == {
        "sqlalchemy",
        "redis.client",
        "softevo.api",
    }


def test_no_source_file_over_400_lines_and_no_function_over_60() -> None:
    """Small modules and functions, the issue's limits (the two numba kernels may stay whole)."""
    kernels = {
        ("core/physics/kernel_one.py", "simulate_one"),
        ("core/physics/kernel_many.py", "simulate_many"),
    }
    long_files, long_functions = [], []
    for package in ("core", "api", "worker", "softevo", "migrations"):
        for path in sorted((ROOT / package).rglob("*.py")):
            name = path.relative_to(ROOT).as_posix()
            text = path.read_text(encoding="utf-8")
            if text.count("\n") > 400:
                long_files.append(name)
            for node in ast.walk(ast.parse(text)):
                if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                    lines = node.end_lineno - node.lineno + 1
                    if lines > 60 and (name, node.name) not in kernels:
                        long_functions.append(f"{name}:{node.name} ({lines})")
    assert long_files == [] and long_functions == []


#: what mypy checks (scripts/lint.sh), and everything else of ours in Python
CHECKED = ("core", "api", "worker", "softevo", "migrations")
ALL = (*CHECKED, "tests", "bench", "scripts", "examples")


def _python_files(folders: tuple[str, ...] = ALL) -> list[Path]:
    return sorted(path for folder in folders for path in (ROOT / folder).rglob("*.py"))


def test_the_code_is_as_the_formatter_writes_it() -> None:
    """No opt-outs from `ruff format`: a long module is split by meaning, not packed by hand."""
    pragma = "fmt: " + "skip"  # spelled apart so that this file holds none
    offenders = [
        f"{path.relative_to(ROOT)}:{number}"
        for path in _python_files()
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if pragma in line or "fmt: " + "off" in line
    ]
    assert offenders == []


def test_every_type_ignore_says_why() -> None:
    """A `# type: ignore[code]` in what mypy checks names its code and gives its reason after it
    or on the line above."""
    offenders = []
    for path in _python_files(CHECKED):
        lines = path.read_text(encoding="utf-8").splitlines()
        for number, line in enumerate(lines, 1):
            if "type: " + "ignore" not in line:
                continue
            after = line.split("type: " + "ignore", 1)[1]
            coded = after.startswith("[")
            reason = "#" in after or (number > 1 and lines[number - 2].strip().startswith("#"))
            if not (coded and reason):
                offenders.append(f"{path.relative_to(ROOT)}:{number}")
    assert offenders == []
