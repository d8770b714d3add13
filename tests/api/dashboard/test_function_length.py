"""The dashboard's own scripts keep every function under 60 lines, as the Python does (STYLE.md):
each function declaration, class method and arrow function with a body given a name
(`const name = (...) => {`) of api/dashboard/static/*.js (not vendor/), from its first line to
the line that closes its braces (issue 35: `runView` had grown to 191)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

STATIC = Path(__file__).resolve().parents[3] / "api" / "dashboard" / "static"
MAX_LINES = 60
#: `function name(`, `export async function name(`, a class method `  name(...) {`, or
#: `const name = (...) => {`
START = re.compile(
    r"^\s*(?:export\s+)?(?:async\s+)?function\s*\*?\s*(\w+)\s*\("
    r"|^\s+(?:static\s+)?(?:async\s+)?(\w+)\s*\([^)]*\)\s*\{\s*$"
    r"|^\s*(?:export\s+)?const\s+(\w+)\s*=\s*(?:async\s*)?\([^)]*\)\s*=>\s*\{\s*$"
)
NOT_METHODS = {"if", "for", "while", "switch", "catch", "function"}


def functions(text: str) -> list[tuple[str, int, int]]:
    """(name, first line, lines) of each function and method in `text`, by brace depth (the
    dashboard's strings and template literals hold balanced braces only)."""
    lines = text.splitlines()
    found = []
    for first, line in enumerate(lines):
        match = START.match(line)
        name = match and (match.group(1) or match.group(2) or match.group(3))
        if not name or name in NOT_METHODS:
            continue
        depth, opened = 0, False
        for last in range(first, len(lines)):
            depth += lines[last].count("{") - lines[last].count("}")
            opened = opened or "{" in lines[last]
            if opened and depth <= 0:
                break
        found.append((name, first + 1, last - first + 1))
    return found


def test_the_counter_counts_a_function_from_its_line_to_its_closing_brace() -> None:
    text = "export async function a(x) {\n  if (x) {\n    return `${x}`;\n  }\n}\n"
    text += "class B {\n  draw(y) {\n    return y;\n  }\n}\n"
    text += "const c = (z) => {\n  return z;\n};\n"
    assert functions(text) == [("a", 1, 5), ("draw", 7, 3), ("c", 11, 3)]


@pytest.mark.parametrize("script", sorted(STATIC.glob("*.js")), ids=lambda path: path.name)
def test_every_dashboard_function_is_under_60_lines(script: Path) -> None:
    found = functions(script.read_text())
    assert found, f"{script.name}: no function found (has the counter gone blind?)"
    long = [f"{name} (line {line}): {n} lines" for name, line, n in found if n > MAX_LINES]
    assert not long, f"{script.name}: " + "; ".join(long)
