"""Shared test fixtures: paths of the repository and its examples."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.services import redis_server, workers  # noqa: F401 - shared fixtures

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def examples() -> Path:
    return ROOT / "examples"
