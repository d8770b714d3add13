"""Shared test fixtures (paths of the repository and its examples), and the fault tests' report:
what each test marked `fault` printed (recovery times, what was killed and when) is repeated in
a section at the end of the run, so CI's output shows the measured figures without `-s`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tests.services import redis_server, workers  # noqa: F401 - shared fixtures

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture
def examples() -> Path:
    return ROOT / "examples"


def pytest_sessionstart(session: pytest.Session) -> None:
    """Before any test starts, the main process (not each xdist worker) has the physics kernels
    loaded, compiling them into numba's cache on a fresh clone: the batched kernel and the one
    for a robot alone in two processes at once (11 s on two cores instead of 18 s on one).
    Otherwise both test processes, RQ workers and `softevo serve` pools would each compile them
    at once, inside whichever timed test came first. (`tests/worker/test_smoke.py` times a cold
    compile in a cache of its own.)"""
    if hasattr(session.config, "workerinput"):
        return
    code = (
        "import sys; from softevo.core.physics.evaluation import warm_up; "
        "warm_up(**{sys.argv[1]: False})"
    )
    warming = [  # each leaves one kernel out
        subprocess.Popen([sys.executable, "-P", "-c", code, skip]) for skip in ("batched", "alone")
    ]
    for process in warming:
        if process.wait() != 0:
            raise pytest.UsageError(
                f"loading the physics kernels failed (exit {process.returncode})"
            )


#: The longest files, longest first (seconds summed over a file's tests, `--durations=0`, 2-core
#: VM, 2026-12-07). A file's tests run together in one process (`--dist loadfile`), so these start
#: first and the short ones fill in beside them, rather than one starting last and running alone.
LONGEST_FIRST = (
    "tests/api/test_crash.py",  # 351 s
    "tests/softevo/test_fresh_clone.py",  # 239 s
    "tests/api/test_schemathesis.py",  # 238 s
    "tests/worker/test_faults.py",  # 194 s
    "tests/softevo/test_reproduce.py",  # 102 s
    "tests/worker/test_smoke.py",  # 99 s
    "tests/api/test_api.py",  # 92 s
    "tests/core/search/test_evolution.py",  # 92 s
    "tests/api/test_database_faults.py",  # 88 s
    "tests/api/dashboard/test_browser.py",  # 77 s
)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """The longest files first (`LONGEST_FIRST`), the others in their usual order after them."""
    rank = {name: place for place, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))


_FAULT_REPORTS: list[tuple[str, list[str]]] = []


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    if report.when == "call" and report.passed and "fault" in report.keywords:
        lines = [line for line in report.capstdout.splitlines() if line.strip()]
        if lines:
            _FAULT_REPORTS.append((report.nodeid, lines))


def pytest_terminal_summary(terminalreporter: Any) -> None:
    if not _FAULT_REPORTS:
        return
    terminalreporter.section("fault tests: what was done and how long recovery took")
    for nodeid, lines in _FAULT_REPORTS:
        terminalreporter.write_line(nodeid)
        for line in lines:
            terminalreporter.write_line(f"    {line}")
