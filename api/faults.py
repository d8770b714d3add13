"""Faults that are said: when the coordinator cannot write (disk full, a read-only database, the
database away), the reason is kept here for `/healthz` and the runs it drives, and the log says
it once a minute with a count, not twice a second with a traceback."""

from __future__ import annotations

import logging
import threading
import time

log = logging.getLogger("softevo.coordinator")
REPEAT_SECONDS = 60.0


def reason(error: BaseException) -> str:
    """The database's own words (SQLAlchemy keeps them in `orig`), first line, bounded."""
    text = str(getattr(error, "orig", None) or error).strip().splitlines()
    return (text[0] if text else type(error).__name__)[:300]


class Faults:
    """The last write failure (cleared by the next write that succeeds), logged rate-limited."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._current: str | None = None
        self._logged: dict[str, tuple[float, int]] = {}  # reason -> (when logged, repeats since)

    def record(self, error: BaseException, where: str) -> None:
        said = reason(error)
        now = time.monotonic()
        with self._lock:
            self._current = said
            logged, repeats = self._logged.get(said, (-REPEAT_SECONDS, 0))
            if now - logged < REPEAT_SECONDS:
                self._logged[said] = (logged, repeats + 1)
                return
            self._logged[said] = (now, 0)
        suffix = f" ({repeats} more times in the last minute)" if repeats else ""
        log.error(
            "%s: cannot write to the database: %s%s", where, said, suffix, exc_info=not repeats
        )

    def clear(self) -> None:
        with self._lock:
            self._current = None

    @property
    def current(self) -> str | None:
        with self._lock:
            return self._current
