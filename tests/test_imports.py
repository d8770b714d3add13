"""`softevo --help`, every subcommand's `--help` and the commands that do not simulate never load
numba (its import alone takes seconds cold); checked in a fresh interpreter, where nothing else
could have imported it first. (The API on Redis: tests/worker/test_smoke.py.)"""

from __future__ import annotations

import json
import subprocess
import sys

HELP_SCRIPT = """
import contextlib, io, json, sys
from softevo.cli import main
loaded = {}
for argv in json.loads(sys.argv[1]):
    with contextlib.redirect_stdout(io.StringIO()), contextlib.suppress(SystemExit):
        main(argv)
    loaded[" ".join(argv)] = [name for name in ("numba", "llvmlite") if name in sys.modules]
print(json.dumps(loaded))
"""
COMMANDS = [
    ["--help"],
    *([name, "--help"] for name in ("run", "simulate", "serve", "worker", "reproduce", "plot")),
    ["export", "--help"],
    ["db", "upgrade", "--help"],
    ["--version"],
]


def test_help_of_every_command_never_imports_numba() -> None:
    done = subprocess.run(
        [sys.executable, "-P", "-c", HELP_SCRIPT, json.dumps(COMMANDS)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    loaded = json.loads(done.stdout)
    assert set(loaded) == {" ".join(argv) for argv in COMMANDS}  # every --help ran
    assert {argv: names for argv, names in loaded.items() if names} == {}


def test_the_check_sees_numba_when_a_command_loads_it() -> None:
    """The same script, with a command that simulates: numba is there (the check can fail)."""
    done = subprocess.run(
        [sys.executable, "-P", "-c", HELP_SCRIPT, json.dumps([["simulate", "missing.json"]])],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert json.loads(done.stdout) == {"simulate missing.json": ["numba", "llvmlite"]}
