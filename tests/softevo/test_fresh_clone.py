"""The README's two set-up commands, as written, in that order, in one new virtual environment in
the root of a fresh copy of the checkout (issue 48): where a new user runs them. Then, from that
root, `softevo run --preset quick`, `softevo serve` with one run, and the library imported.

The one change to the commands: the test command's `python -m pytest` collects the suite
(`--collect-only`) instead of running it inside itself. numba's cache starts empty (a user cache
folder of the test's own), so the kernels compile as on a new machine: the slowest test file.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from tests.softevo.installed import ROOT, clean_env

pytestmark = pytest.mark.slow

#: The suite run inside itself would never end: the test command collects it instead.
COLLECT = "python -m pytest --collect-only -q"


def readme_commands() -> tuple[str, str]:
    """The README's first two shell blocks: the experiment, then the tests."""
    blocks = re.findall(r"```sh\n(.*?)\n```", (ROOT / "README.md").read_text(), re.S)
    first, second = blocks[0].strip(), blocks[1].strip()
    assert "softevo run" in first and "python -m pytest" in second, blocks[:2]
    return first, second


def fresh_copy(where: Path) -> Path:
    """What `git clone` of this working tree gives: its tracked and new (not ignored) files."""
    listed = subprocess.run(
        ["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT,
        check=True,
        capture_output=True,
    ).stdout.split(b"\0")
    clone = where / "softevo"
    for name in filter(None, (entry.decode() for entry in listed)):
        if (ROOT / name).is_file():
            (clone / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, clone / name)
    return clone


def user_env(clone: Path, home: Path) -> dict[str, str]:
    """A shell in the clone's virtual environment, with an empty user cache (numba's) and pip's
    own download cache kept (the packages are the same; only their download is skipped)."""
    pip_cache = subprocess.run(
        [sys.executable, "-m", "pip", "cache", "dir"], capture_output=True, text=True
    ).stdout.strip()
    env = clean_env()
    env.pop("NUMBA_CACHE_DIR", None)
    venv = clone / ".venv"
    env |= {
        "VIRTUAL_ENV": str(venv),
        "PATH": f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}",
        "XDG_CACHE_HOME": str(home / "cache"),
        "PIP_CACHE_DIR": pip_cache or str(home / "pip"),
        "SOFTEVO_DATABASE_URL": f"sqlite:///{home / 'served.db'}",
    }
    return env


def shell(command: str, clone: Path, env: dict[str, str], timeout: float) -> str:
    done = subprocess.run(
        ["bash", "-c", command],
        cwd=clone,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        stdin=subprocess.DEVNULL,
    )
    assert done.returncode == 0, f"{command}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return done.stdout


def serve_one_run(clone: Path, env: dict[str, str]) -> dict:
    """`softevo serve` started in the clone's root; one small run through it, to the end."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    server = subprocess.Popen(
        ["softevo", "serve", "--host", "127.0.0.1", "--port", str(port)],
        cwd=clone,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    url = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                if httpx.get(f"{url}/healthz", timeout=2).status_code == 200:
                    break
            except httpx.HTTPError:
                time.sleep(0.2)
        config = {"preset": "quick", "seed": 2, "generations": 3}
        run = httpx.post(f"{url}/runs", json=config, timeout=10).json()
        while time.monotonic() < deadline + 60:
            state = httpx.get(f"{url}/runs/{run['id']}", timeout=5).json()
            if state["status"] not in ("queued", "running"):
                break
            time.sleep(0.3)
        assert state["status"] == "completed", state
        return httpx.get(f"{url}/runs/{run['id']}/curve", timeout=5).json()
    finally:
        server.terminate()
        server.wait(timeout=30)


def numba_files(folder: Path) -> list[Path]:
    return [*folder.rglob("*.nbi"), *folder.rglob("*.nbc")]


def test_the_readme_commands_work_in_a_fresh_clones_root(tmp_path: Path) -> None:
    first, second = readme_commands()
    clone = fresh_copy(tmp_path)
    env = user_env(clone, tmp_path)
    subprocess.run([sys.executable, "-m", "venv", str(clone / ".venv")], check=True)
    said = shell(first, clone, env, timeout=600)  # pip install . && softevo run --preset quick
    assert "results in softevo-runs/" in said, said
    site = next((clone / ".venv" / "lib").glob("python*/site-packages"))
    assert not numba_files(site), "numba's cache went into the installed package"
    assert numba_files(tmp_path / "cache" / "softevo" / "numba")
    library = "from softevo import library; print(library.simulate.__module__)"
    shell(f"python -c '{library}'", clone, env, timeout=120)

    shell(second.replace("python -m pytest", COLLECT), clone, env, timeout=600)
    where = "import softevo.core; print(softevo.core.__file__)"
    assert shell(f"python -c '{where}'", clone, env, 60).strip() == str(clone / "core/__init__.py")
    again = shell("softevo run --preset quick --seed 3 --json", clone, env, timeout=300)
    rows = json.loads(again)["generations"]
    assert len(rows) == 20 and rows[-1]["best_so_far"] > 0
    curve = serve_one_run(clone, env)
    assert [row["generation"] for row in curve["generations"]] == [0, 1, 2]
