"""The kernels' numba options, and where numba keeps their compiled code.

numba caches a compiled kernel beside its source by default, which for an installed softevo is
the package folder: files pip never recorded, so they outlive `pip uninstall` and the folder
left behind then shadows the next install (an editable one fails to import). The cache goes to a
user cache folder instead, unless `NUMBA_CACHE_DIR` names one: `$XDG_CACHE_HOME/softevo/numba`
(`~/.cache/softevo/numba`), or a folder of the temporary directory where home is not writable.
numba keys every cached kernel on its source file's path and time stamp, so two installs never
share (or spoil) each other's entries.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Literal, TypedDict

import numba


def user_cache_folder() -> Path:
    """The folder numba's cache goes to when `NUMBA_CACHE_DIR` is unset."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    folder = Path(base) / "softevo" / "numba"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):
            pass  # writable
    except OSError:
        user = os.getuid() if hasattr(os, "getuid") else os.getlogin()
        folder = Path(tempfile.gettempdir()) / f"softevo-numba-{user}"
        folder.mkdir(parents=True, exist_ok=True)
    return folder


def use_cache_folder() -> None:
    """Point numba's cache (and that of every process started from here: the pool's fork server,
    its processes) at `NUMBA_CACHE_DIR`, or at `user_cache_folder()` where it is unset. numba reads
    the variable when it is imported, so its setting is also written where numba looks now."""
    if not os.environ.get("NUMBA_CACHE_DIR"):
        os.environ["NUMBA_CACHE_DIR"] = str(user_cache_folder())
    # numba.config makes its names at import time from the environment, so a checker sees none
    numba.config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]  # type: ignore[attr-defined]


use_cache_folder()


#: Options of every kernel: cached, callable without the GIL, plain IEEE arithmetic (numpy's error
#: model and no fastmath), no bounds checks.
class JitOptions(TypedDict):
    """numba's keyword options, typed so that `njit(**JIT)` is checked."""

    cache: bool
    nogil: bool
    error_model: Literal["numpy"]
    boundscheck: bool


JIT: JitOptions = {"cache": True, "nogil": True, "error_model": "numpy", "boundscheck": False}
