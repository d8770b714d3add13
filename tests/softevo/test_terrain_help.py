"""`--help` of `softevo run` and `softevo simulate` shows an example of every kind of ground
that is not flat, each one a terrain the config accepts as written (issue 39)."""

from __future__ import annotations

import json
import re

import pytest

from softevo.core.config import resolve
from softevo.run_arguments import TERRAIN_EXAMPLES
from tests.softevo.inprocess import softevo


def test_every_example_is_a_terrain_and_every_kind_has_one() -> None:
    examples = [json.loads(text) for text in re.findall(r"'(\{.*?\})'", TERRAIN_EXAMPLES)]
    kinds = [example["kind"] for example in examples]
    assert set(kinds) >= {"slope", "steps", "rough", "hurdles"}, kinds
    for example in examples:
        assert resolve({"preset": "quick", "sim": {"terrain": example}}).sim.terrain.kind


@pytest.mark.parametrize("command", ["run", "simulate"])
def test_help_shows_them(command: str) -> None:
    done = softevo(command, "--help")
    text = " ".join(done.stdout.split())  # argparse wraps lines
    assert all(f'"kind": "{kind}"' in text for kind in ("steps", "rough", "hurdles")), text
