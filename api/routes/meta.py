"""`/healthz`, `/presets` and `/algorithms`."""

from __future__ import annotations

from collections.abc import Sequence

from fastapi import APIRouter, Response

from softevo.api.coordinator import Coordinator
from softevo.api.deps import CoordinatorDep, DatabaseDep, SettingsDep, TrustedDep
from softevo.api.schemas import AlgorithmPublic, Health, Preset
from softevo.api.settings import Settings
from softevo.core.config import PRESET_DESCRIPTIONS, PRESETS
from softevo.core.search.configured import describe_strategies

router = APIRouter(tags=["meta"])


@router.get("/healthz", responses={503: {"model": Health}})
def healthz(
    db: DatabaseDep,
    settings: SettingsDep,
    coordinator: CoordinatorDep,
    trusted: TrustedDep,
    response: Response,
) -> Health:
    """The database and, when configured, Redis; 503 when either is down. Internals (the
    exception, the coordinator) only for a caller with the token, when one is set."""
    database = redis = "ok"
    try:
        db.ping()
    except Exception as error:
        database = f"down: {type(error).__name__}"
    if settings.redis_url is None:
        redis = "not configured"
    else:
        try:
            import redis as redis_client

            client = redis_client.Redis.from_url(
                settings.redis_url, socket_connect_timeout=1, socket_timeout=1
            )
            client.ping()
        except Exception as error:
            redis = f"down: {type(error).__name__}"
    fault = coordinator.faults.current  # the coordinator's last write failed: said here
    if database == "ok" and fault is not None:
        database = f"cannot write: {fault}"
    healthy = database == "ok" and redis in ("ok", "not configured")
    if not healthy:
        response.status_code = 503
    workers = idle_workers(coordinator, settings)
    internals: dict[str, Sequence[object]] | None = {
        "owner": coordinator.owner,
        "driving": coordinator.active,
    }
    if not trusted:
        database, redis, internals = database.split(":")[0], redis.split(":")[0], None
    return Health(
        status="ok" if healthy else "degraded",
        database=database,
        redis=redis,
        workers=workers,
        coordinator=internals,
    )


def idle_workers(coordinator: Coordinator, settings: Settings) -> str | None:
    """With Redis: "ok" while the queue has a live worker; past SOFTEVO_NO_WORKER_SECONDS
    without one, how long (said on `/healthz` and on active runs). None without Redis."""
    without = getattr(coordinator.driving.evaluator, "without_workers", None)
    if without is None:
        return None
    try:
        seconds = without()
    except Exception:  # Redis away: `redis` says so already
        return None
    if seconds < settings.no_worker_seconds:
        return "ok"
    return f"no live worker on the queue for {seconds:.0f} s: start `softevo worker`"


@router.get("/presets")
def presets() -> list[Preset]:
    """The named starting points of `POST /runs`, with their settings."""
    return [
        Preset(name=name, description=PRESET_DESCRIPTIONS[name], settings=settings)
        for name, settings in PRESETS.items()
    ]


@router.get("/algorithms")
def algorithms() -> list[AlgorithmPublic]:
    """The installed search strategies (entry-point group `softevo.strategies`): what a run's
    `algorithm` may name, the shared settings each reads and the schema of its own `options`."""
    return [AlgorithmPublic.model_validate(entry) for entry in describe_strategies()]
