"""docs/python.md runs as written: each `## ` section's ```python blocks, in order, in one fresh
interpreter (a section builds on its earlier blocks, never on another section's)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

DOC = Path(__file__).resolve().parents[2] / "docs" / "python.md"
BLOCK = re.compile(r"^```python\n(.*?)^```$", re.MULTILINE | re.DOTALL)
#: What a section must print besides running cleanly (a block that silently does nothing fails).
PRINTS = {
    "The service (the client)": ["completed", "best speed: ", "softevo.robot/1", "422 population"],
    "In-process (the library)": [
        "3 best ",
        "best speed: ",
        "same speed as in the run: True",
        " 31 frames",
        "generation 3: diversity",
        "stepped like evolve: True",
        "archive coverage: ",
        "ConfigError: population: ",
        "RobotFileError: sim.duration: ",
    ],
}


def sections() -> dict[str, str]:
    """Heading -> the code of its python blocks, joined in order."""
    found: dict[str, str] = {}
    for part in re.split(r"^## ", DOC.read_text(), flags=re.MULTILINE)[1:]:
        heading, _, body = part.partition("\n")
        code = "\n".join(BLOCK.findall(body))
        if code:
            found[heading.strip()] = code
    return found


def test_the_client_and_library_sections_are_there() -> None:
    assert set(PRINTS) <= set(sections())


@pytest.mark.parametrize("heading", sorted(sections()))
def test_a_sections_code_runs(heading: str, tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-P", "-c", sections()[heading]],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, f"docs/python.md, {heading}:\n{done.stdout}\n{done.stderr}"
    for words in PRINTS.get(heading, []):
        assert words in done.stdout, f"{heading} did not print {words!r}:\n{done.stdout}"
