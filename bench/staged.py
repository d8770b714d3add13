"""Another checkout staged as it would be installed, for the benches that compare two trees
(`coordinator.py --tree`, `same_results.py --tree`).

A staged tree must also find its own strategies: the installed checkout's entry points name its
own module paths (`softevo.core.search...`), which an older tree lays out differently or not at
all. Imports nothing of softevo, so `own_strategies` can run before softevo is imported.
"""

from __future__ import annotations

import importlib.metadata as metadata
import shutil
import tempfile
import tomllib
from pathlib import Path
from typing import Any


def stage(tree: Path) -> Path:
    """A folder where `import softevo` finds `tree`'s code as installed, with its pyproject."""
    staged = Path(tempfile.mkdtemp(prefix="softevo-tree-"))
    shutil.copytree(tree / "softevo", staged / "softevo")
    for folder in ("core", "api", "worker", "migrations"):
        shutil.copytree(tree / folder, staged / "softevo" / folder)
    shutil.copy(tree / "pyproject.toml", staged / "pyproject.toml")
    return staged


def own_strategies(staged: Path) -> None:
    """Make `importlib.metadata.entry_points` answer the staged tree's own groups (a tree with
    none keeps the installed ones, which it never reads)."""
    pyproject = staged / "pyproject.toml"
    if not pyproject.exists():
        return
    with pyproject.open("rb") as handle:
        groups = tomllib.load(handle)["project"].get("entry-points", {})
    mine = metadata.EntryPoints(
        metadata.EntryPoint(name, value, group)
        for group, names in groups.items()
        for name, value in names.items()
    )
    installed = metadata.entry_points

    def entry_points(**selection: Any) -> Any:
        if selection.get("group") in groups:
            return mine.select(**selection)
        return installed(**selection)

    metadata.entry_points = entry_points  # type: ignore[assignment]
