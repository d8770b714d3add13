"""Service settings, read once from the environment (`SOFTEVO_*`) by `get_settings()`.

Every setting has a default that runs a real experiment on a fresh machine: SQLite in
`./softevo.db`, an in-process worker pool, no token (and reads open: SOFTEVO_PROTECT_READS=1
closes them with the token). Ceilings bound what one `POST /runs` may ask
for, so a request that would occupy the service for days is refused before anything is queued.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, fields
from functools import lru_cache

from softevo.core.limits import (
    BATCH_SIZE,
    IN_FLIGHT,
    MAX_VOXELS,
    SAVE_SECONDS,
    SERVICE_MAX_VOXELS,
)

DEFAULT_DATABASE_URL = "sqlite:///softevo.db"


@dataclass(frozen=True)
class Limits:
    """Ceilings on one run, checked at `POST /runs` (422 naming the field when exceeded)."""

    max_population: int = 1000
    max_generations: int = 10_000
    max_voxels: int = SERVICE_MAX_VOXELS
    max_duration: float = 60.0  # simulated seconds per robot
    min_dt: float = 1e-4  # s
    max_evaluations: int = 1_000_000  # population x generations
    max_sweep_runs: int = 200
    max_queued: int = 1000  # runs waiting to start; more are refused with 429
    max_body_bytes: int = 1_048_576  # a request body over this is refused with 413
    max_event_clients: int = 500  # open event streams (GET /runs/{id}/events) of this process
    # one accepted run or sweep (the sum of its runs), counted before anything runs (api.cost)
    max_spring_steps: float = 1e13  # springs of the box x steps x simulations asked for
    max_stored_bytes: int = 2_000_000_000  # every individual's row with its genome


@dataclass(frozen=True)
class Settings:
    """How this process serves: where it stores, how it evaluates, how many runs at once."""

    database_url: str = DEFAULT_DATABASE_URL
    redis_url: str | None = None
    api_token: str | None = None
    protect_reads: bool = False  # every GET needs api_token too (but /healthz and the dashboard)
    max_running: int = 2  # runs driven at once by this process; the rest wait, queued
    workers: int | None = None  # in-process pool size (default: one per core)
    batch_size: int = BATCH_SIZE  # robots per evaluator call
    queued_batches: int = IN_FLIGHT  # batches of one run in flight at once
    save_seconds: float = SAVE_SECONDS  # a batch landing sooner after the run's last write waits
    replay_seconds: float = 600.0  # with Redis: a replay GET waits at most this for a worker
    no_worker_seconds: float = 60.0  # with Redis: a queue without a live worker this long is said
    lease_seconds: float = 15.0  # a coordinator that stops heartbeating loses its runs after this
    poll_seconds: float = 0.5  # how often the scheduler looks for runs (backing off while idle)
    header_seconds: float = 10.0  # a request's head (line and headers) must arrive within this
    keep_alive_seconds: float = 5.0  # an idle keep-alive connection is closed after this
    limits: Limits = field(default_factory=Limits)

    @classmethod
    def from_env(cls, environ: dict[str, str] | None = None) -> Settings:
        """Settings from `SOFTEVO_*` variables; a bad value raises ValueError naming it."""
        env = dict(os.environ if environ is None else environ)
        values: dict[str, object] = {}
        for item in fields(cls):
            if item.name == "limits":
                continue
            raw = env.get(f"SOFTEVO_{item.name.upper()}")
            if raw is not None and raw != "":
                values[item.name] = _parse(f"SOFTEVO_{item.name.upper()}", raw, item.type)
        limits: dict[str, object] = {}
        for item in fields(Limits):
            raw = env.get(f"SOFTEVO_{item.name.upper()}")
            if raw is not None and raw != "":
                limits[item.name] = _parse(f"SOFTEVO_{item.name.upper()}", raw, item.type)
        settings = cls(**values, limits=Limits(**limits))  # type: ignore[arg-type]
        for name in ("max_running", "batch_size", "queued_batches"):
            if getattr(settings, name) < 1:
                raise ValueError(f"SOFTEVO_{name.upper()}: must be >= 1")
        if settings.limits.max_queued < 1 or settings.limits.max_body_bytes < 1024:
            raise ValueError("SOFTEVO_MAX_QUEUED must be >= 1, SOFTEVO_MAX_BODY_BYTES >= 1024")
        if not 1 <= settings.limits.max_voxels <= MAX_VOXELS:
            raise ValueError(f"SOFTEVO_MAX_VOXELS: must be between 1 and {MAX_VOXELS}")
        if settings.protect_reads and not settings.api_token:
            raise ValueError(
                "SOFTEVO_PROTECT_READS=1 needs SOFTEVO_API_TOKEN: the token reads are closed with"
            )
        if settings.workers is not None and settings.workers < 1:
            raise ValueError("SOFTEVO_WORKERS: must be >= 1")
        if settings.lease_seconds <= 0 or settings.poll_seconds <= 0:
            raise ValueError("SOFTEVO_LEASE_SECONDS and SOFTEVO_POLL_SECONDS must be > 0")
        if not 0 <= settings.save_seconds < math.inf:
            raise ValueError("SOFTEVO_SAVE_SECONDS: must be a number >= 0 (0: every batch at once)")
        for name in ("header_seconds", "keep_alive_seconds"):
            if not 0 < getattr(settings, name) < math.inf:
                raise ValueError(f"SOFTEVO_{name.upper()}: must be a number of seconds > 0")
        return settings


_SWITCH = {
    "1": True,
    "true": True,
    "yes": True,
    "on": True,
    "0": False,
    "false": False,
    "no": False,
    "off": False,
}


def _parse(name: str, raw: str, kind: object) -> object:
    kind = str(kind)
    if kind == "bool":
        if raw.strip().lower() not in _SWITCH:
            raise ValueError(f"{name}: expected 1 or 0 (true or false), got {raw!r}")
        return _SWITCH[raw.strip().lower()]
    try:
        if "int" in kind:
            return int(raw)
        if "float" in kind:
            return float(raw)
    except ValueError:
        raise ValueError(f"{name}: expected a number, got {raw!r}") from None
    return raw


@lru_cache
def get_settings() -> Settings:
    return Settings.from_env()
