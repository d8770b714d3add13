"""softevo as `pip install .` leaves it: the wheel built from a copy of the checkout, installed in
a fresh virtual environment whose dependencies are this one's (a .pth line), for tests that run
it from a folder that is not the repository, so nothing can be read from the checkout (issue 19:
`softevo reproduce` read examples/ next to the source and crashed once installed)."""

from __future__ import annotations

import os
import shutil
import site
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: What pyproject.toml builds the wheel from.
PACKAGED = ("pyproject.toml", "README.md", "softevo", "core", "api", "worker", "migrations", "docs")


def clean_env() -> dict[str, str]:
    """The environment without anything that would put the checkout on the path."""
    return {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}


def install_wheel(work: Path) -> Path:
    """A venv in `work` holding the built wheel; its dependencies come from this venv's
    site-packages through a .pth line (added after its own site-packages, so its softevo comes
    first). Returns the venv's folder."""
    source = work / "source"  # a copy: building in the checkout would leave a build/ whose
    # stale files (of modules since deleted) would go into later wheels
    source.mkdir()
    for name in PACKAGED:
        if (ROOT / name).is_dir():
            ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
            shutil.copytree(ROOT / name, source / name, ignore=ignore)
        else:
            shutil.copy2(ROOT / name, source / name)
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "-q",
            "-w",
            str(work / "dist"),
            str(source),
        ],
        check=True,
        capture_output=True,
        timeout=300,
    )
    (wheel,) = (work / "dist").glob("softevo-*.whl")
    venv = work / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / "bin" / "python"
    purelib = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    Path(purelib, "dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "--python",
            str(python),
            "install",
            "--no-deps",
            "--no-index",
            "-q",
            str(wheel),
        ],
        check=True,
        capture_output=True,
        timeout=300,
        env=clean_env(),
    )
    return venv
