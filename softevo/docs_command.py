"""`softevo docs [NAME]`: the guides that `--help` points to (docs/tasks.md, docs/physics.md,
...), shipped in the wheel as `softevo.docs` so they are there after `pip install`, not only in
a checkout of the repository. Without NAME it lists them; with NAME it prints one as Markdown."""

from __future__ import annotations

import argparse
from importlib import resources
from pathlib import Path
from typing import Any

from softevo.command_error import CommandError


def add_parser(commands: Any) -> None:
    docs = commands.add_parser(
        "docs",
        help="list the guides --help points to (docs/*.md), or print one",
        description="The project's guides, installed with it: `softevo docs` lists them with "
        "their titles, `softevo docs tasks` prints docs/tasks.md as Markdown (pipe it to a "
        "pager or a Markdown viewer).",
    )
    docs.add_argument(
        "name", nargs="?", metavar="NAME", help="a guide, e.g. tasks or docs/tasks.md"
    )
    docs.set_defaults(handler=docs_command)


def guides() -> dict[str, Any]:
    """Guide name -> a readable path: the installed `softevo.docs`, else the checkout's docs/
    (an editable install maps only the Python packages)."""
    try:
        folder: Any = resources.files("softevo.docs")
        found = {item.name[:-3]: item for item in folder.iterdir() if item.name.endswith(".md")}
    except (ModuleNotFoundError, FileNotFoundError, NotADirectoryError):
        found = {}
    if not found:
        checkout = Path(__file__).resolve().parent.parent / "docs"
        found = {path.stem: path for path in checkout.glob("*.md")}
    return dict(sorted(found.items()))


def docs_command(args: argparse.Namespace) -> int:
    available = guides()
    if not available:
        raise CommandError("no guides found: this installation carries no softevo.docs")
    if args.name is None:
        for name, path in available.items():
            title = next((line for line in path.read_text().splitlines() if line.strip()), "")
            print(f"{name:12s} {title.lstrip('# ')}")
        return 0
    name = Path(args.name).name.removesuffix(".md")
    if name not in available:
        raise CommandError(f"no guide {args.name!r} (guides: {', '.join(available)})")
    print(available[name].read_text(), end="")
    return 0
