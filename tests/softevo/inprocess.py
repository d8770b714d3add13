"""`softevo ARGS` called in this process (`softevo.cli.main`), its exit code and what it printed:
what a user sees, without a subprocess's start-up (the tests about processes start real ones)."""

from __future__ import annotations

import contextlib
import io
import os
from dataclasses import dataclass
from pathlib import Path

from softevo.cli import main


@dataclass(frozen=True)
class Done:
    returncode: int
    stdout: str
    stderr: str


def softevo(*args: str, cwd: Path | None = None) -> Done:
    out, err = io.StringIO(), io.StringIO()
    with (
        contextlib.redirect_stdout(out),
        contextlib.redirect_stderr(err),
        contextlib.chdir(cwd or os.getcwd()),
    ):
        try:
            code = main(list(args))
        except SystemExit as exit_:  # argparse: usage errors (2), --help and --version (0)
            code = exit_.code if isinstance(exit_.code, int) else (0 if exit_.code is None else 1)
            if isinstance(exit_.code, str):
                err.write(exit_.code + "\n")
    return Done(code, out.getvalue(), err.getvalue())
