"""softevo: evolve modular soft crawling robots. The `softevo` command lives in `softevo.cli`.

The repository keeps `core/`, `api/`, `worker/` and `migrations/` beside this folder, and the
install maps them under `softevo`. Python started in a checkout's root finds this folder before
the installed package, so there the checkout's root also serves as a folder of the package:
`softevo.core` is then `core/`, the same code the install holds.
"""

from pathlib import Path

__version__ = "0.1.0"

_checkout = Path(__file__).resolve().parent.parent
if not Path(__file__).with_name("core").is_dir() and (_checkout / "core" / "physics").is_dir():
    __path__.append(str(_checkout))
