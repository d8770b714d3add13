"""`pip install softevo` is the CLI alone (issue 48): without the `service` extra's packages,
`softevo run --preset quick` and the other in-process commands work, and `serve`, `worker`,
`reproduce` and `plot RUN_ID` say in one line which extra to install. The packages are made
absent in a fresh interpreter (None in sys.modules: their import fails, find_spec finds none),
which is what a venv without them gives, without building one."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.softevo.installed import ROOT

#: The `service` extra (pyproject.toml) and what only it brings in.
ABSENT = ("fastapi", "starlette", "uvicorn", "h11", "httpx", "httpcore", "redis", "rq", "psycopg")

SCRIPT = """
import contextlib, io, json, sys
for name in json.loads(sys.argv[1]):
    sys.modules[name] = None
from softevo.cli import main
said = []
for argv in json.loads(sys.argv[2]):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exit_:
            code = exit_.code
    said.append([code, out.getvalue(), err.getvalue()])
print(json.dumps(said))
"""


def _commands(argvs: list[list[str]], cwd: Path) -> list[tuple[int, str, str]]:
    command = [sys.executable, "-P", "-c", SCRIPT, json.dumps(ABSENT), json.dumps(argvs)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=600, cwd=cwd)
    assert done.returncode == 0, done.stderr
    return [tuple(item) for item in json.loads(done.stdout)]


@pytest.mark.slow
def test_the_in_process_commands_need_no_service_package(tmp_path: Path) -> None:
    robot = str(ROOT / "examples" / "crawler_4x4x4.json")
    small = ["--population", "4", "--generations", "2", "--duration", "1", "--workers", "1"]
    argvs = [
        ["run", "--preset", "quick", *small, "--out", "run"],
        ["plot", "run", "--out", "run.png"],
        ["simulate", robot, "--duration", "1.5"],
        ["replay", robot, "--out", "c.gif", "--duration", "1", "--fps", "2"],
        ["export", robot, "--out", "c.stl"],
        ["algorithms"],
        ["docs", "tasks"],
    ]
    for argv, (code, _, err) in zip(argvs, _commands(argvs, tmp_path), strict=True):
        assert code == 0, (argv, err)
    assert (tmp_path / "run" / "best_robot.json").is_file() and (tmp_path / "run.png").is_file()


def test_the_service_commands_say_which_extra_to_install(tmp_path: Path) -> None:
    argvs = [
        ["serve"],
        ["worker", "--url", "redis://127.0.0.1:1"],
        ["reproduce", "--quick", "--out", "r"],
        ["plot", "3", "--out", "p.png"],
    ]
    for argv, (code, _, err) in zip(argvs, _commands(argvs, tmp_path), strict=True):
        assert code == 1 and err.count("\n") == 1, (argv, err)
        assert err.startswith(f"softevo {argv[0]}: error: ") and "Traceback" not in err
        assert "pip install 'softevo[service]'" in err, err
    assert not (tmp_path / "r").exists()  # said before anything was made


def test_the_python_client_says_which_extra_to_install() -> None:
    script = "import sys; sys.modules['httpx'] = None; import softevo.client"
    done = subprocess.run(
        [sys.executable, "-P", "-c", script], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 1 and "pip install 'softevo[service]'" in done.stderr
