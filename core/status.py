"""The life cycles of a run and of its individuals, named once: the service stores them, its API
serves them and its clients (`softevo reproduce`, the dashboard) read them."""

from __future__ import annotations

from enum import StrEnum


class RunStatus(StrEnum):
    QUEUED = "queued"
    RUNNING = "running"
    COMPLETED = "completed"
    FAILED = "failed"
    CANCELLED = "cancelled"

    @property
    def active(self) -> bool:
        """Still to be driven: only an active run can be cancelled or taken over."""
        return self in ACTIVE

    @property
    def final(self) -> bool:
        return not self.active


ACTIVE = frozenset({RunStatus.QUEUED, RunStatus.RUNNING})
FINAL = frozenset(RunStatus) - ACTIVE


class IndividualStatus(StrEnum):
    """pending: waiting for fitness; evaluated: simulated in this generation; cached: the same
    genome as an earlier generation's, fitness copied; failed: the simulation failed (no
    fitness, never 0)."""

    PENDING = "pending"
    EVALUATED = "evaluated"
    CACHED = "cached"
    FAILED = "failed"
