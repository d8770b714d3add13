"""The one error every `softevo` command reports as a single line on stderr, with exit code 1
(its own module, so the command modules and `softevo.cli`, which dispatches them, do not
import each other)."""

from __future__ import annotations


class CommandError(Exception):
    """A failure to report as one line on stderr, with exit code 1."""
