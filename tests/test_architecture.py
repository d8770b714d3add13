"""The boundary the user asked for: `core` imports none of the service's packages, `worker` does
not import the API. Checked on every import statement of the source, so it fails as soon as one
is added."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
FORBIDDEN = {
    "core": {
        *("api", "worker", "softevo"),
        *("sqlalchemy", "redis", "rq", "fastapi", "alembic", "uvicorn"),
    },
    "worker": {"api", "fastapi", "sqlalchemy", "alembic", "uvicorn"},
}


def imported_modules(path: Path) -> set[str]:
    """Top-level names of every module imported anywhere in a file (also inside functions)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_does_not_import_forbidden_modules(package: str) -> None:
    files = sorted((ROOT / package).rglob("*.py"))
    assert files, f"no source files found in {package}/"
    offenders = {
        f"{path.relative_to(ROOT)} imports {name}"
        for path in files
        for name in imported_modules(path) & FORBIDDEN[package]
    }
    assert not offenders, sorted(offenders)


def test_checker_catches_a_forbidden_import(tmp_path: Path) -> None:
    source = tmp_path / "bad.py"
    source.write_text("def f():\n    from sqlalchemy import select\n    import redis.client\n")
    assert imported_modules(source) >= {"sqlalchemy", "redis"}
