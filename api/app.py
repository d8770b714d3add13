"""The FastAPI application: `create_app()` builds it; resources are made in the lifespan.

On start: open the database (the embedded SQLite default is migrated on the spot; PostgreSQL must
be at the latest migration, `softevo db upgrade`), make the evaluator and start the coordinator,
which takes over any run whose lease has expired. On stop: hand the runs back at once.
"""

from __future__ import annotations

import gc
import logging
import re
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from typing import Any

from alembic.script import ScriptDirectory
from fastapi import FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from sqlalchemy.exc import InterfaceError, OperationalError
from starlette.exceptions import HTTPException as StarletteHTTPException

from softevo.api import dashboard, pictures, replay, store
from softevo.api.body_limit import BodyLimitMiddleware
from softevo.api.coordinator import Coordinator
from softevo.api.db import Database, alembic_config, current_revision
from softevo.api.events import TooManyClientsError, Watches
from softevo.api.read_token import ReadTokenMiddleware
from softevo.api.routes import meta, runs, sweeps
from softevo.api.settings import Settings, get_settings
from softevo.api.validation import RequestError, point_to_sim
from softevo.core.evaluator import Evaluator

log = logging.getLogger("softevo.api")


class DatabaseNotMigratedError(RuntimeError):
    pass


def check_migrated(db: Database) -> None:
    head = ScriptDirectory.from_config(alembic_config()).get_current_head()
    found = current_revision(db.engine)
    if found != head:
        raise DatabaseNotMigratedError(
            f"database is at migration {found or 'none'}, expected {head}: run `softevo db upgrade`"
        )


def default_evaluator(settings: Settings) -> Evaluator:
    """RQ workers when SOFTEVO_REDIS_URL is set (this process then never loads the physics),
    otherwise a pool of local processes."""
    if settings.redis_url:
        from softevo.worker.evaluator import RQEvaluator

        return RQEvaluator(settings.redis_url)
    from softevo.core.physics.evaluation import make_evaluator

    return make_evaluator(settings.workers)


def _replays_on_workers(settings: Settings) -> Any:
    """With Redis, replays are computed by the RQ workers too (this process never loads the
    physics); the replayer, to close at shutdown, or None."""
    if not settings.redis_url:
        return None
    from softevo.worker.evaluator import RQReplayer

    replayer = RQReplayer(settings.redis_url, timeout=settings.replay_seconds)
    replay.use_workers(replayer)
    return replayer


def create_app(
    settings: Settings | None = None,
    evaluator_factory: Callable[[Settings], Evaluator] | None = None,
) -> FastAPI:
    settings = settings or get_settings()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        db = Database(settings.database_url)
        if db.is_sqlite:
            db.upgrade()
        else:
            check_migrated(db)
        evaluator = (evaluator_factory or default_evaluator)(settings)
        coordinator = Coordinator(
            db,
            evaluator,
            max_running=settings.max_running,
            batch_size=settings.batch_size,
            in_flight=settings.queued_batches,
            save_seconds=settings.save_seconds,
            lease_seconds=settings.lease_seconds,
            poll_seconds=settings.poll_seconds,
        )
        app.state.settings, app.state.db, app.state.coordinator = settings, db, coordinator
        replayer = _replays_on_workers(settings)
        app.state.watches = Watches(db, settings.limits.max_event_clients)
        coordinator.start()
        # What start-up loaded stays for the life of the process: keep it out of the cyclic
        # collector's full passes, which otherwise add ~100 ms to a large response now and then
        # (BENCHMARKS.md, API latency).
        gc.freeze()
        try:
            yield
        finally:
            coordinator.stop()
            evaluator.close()
            if replayer is not None:
                replay.use_workers(None)
                replayer.close()
            replay.shutdown()  # the replays' own processes, if this server made any
            db.dispose()

    app = FastAPI(
        title="softevo",
        summary="Evolve modular soft crawling robots",
        version="0.1.0",
        lifespan=lifespan,
        docs_url=None,  # served from the package by `dashboard.install` (offline)
        redoc_url=None,  # ReDoc loads its script from a CDN
    )
    _install_middleware(app, settings)
    for module in (runs, sweeps, meta):
        app.include_router(module.router)
    dashboard.install(app)
    _install_error_handlers(app)
    return app


def _install_middleware(app: FastAPI, settings: Settings) -> None:
    """The body limit, and with SOFTEVO_PROTECT_READS the read token around it (the outermost:
    a refused read costs nothing)."""
    app.add_middleware(BodyLimitMiddleware, max_bytes=settings.limits.max_body_bytes)
    if settings.protect_reads and settings.api_token:
        app.add_middleware(ReadTokenMiddleware, token=settings.api_token)


def _install_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(store.NotFoundError)
    async def not_found(_request: Request, error: store.NotFoundError) -> JSONResponse:
        return JSONResponse({"detail": str(error)}, status_code=404)

    @app.exception_handler(store.ConflictError)
    async def conflict(_request: Request, error: store.ConflictError) -> JSONResponse:
        return JSONResponse({"detail": str(error)}, status_code=409)

    @app.exception_handler(store.QueueFullError)
    async def queue_full(_request: Request, error: store.QueueFullError) -> JSONResponse:
        return JSONResponse({"detail": str(error)}, status_code=429, headers={"Retry-After": "30"})

    @app.exception_handler(TooManyClientsError)
    @app.exception_handler(replay.ReplayUnavailableError)
    @app.exception_handler(replay.ReplayBusyError)
    async def no_replay(_request: Request, error: Exception) -> JSONResponse:
        return JSONResponse({"detail": str(error)}, status_code=503, headers={"Retry-After": "2"})

    @app.exception_handler(pictures.PictureUnsupportedError)
    async def unsupported(_request: Request, error: Exception) -> JSONResponse:
        return JSONResponse({"detail": str(error)}, status_code=501)

    @app.exception_handler(RequestError)
    async def bad_request(_request: Request, error: RequestError) -> JSONResponse:
        return JSONResponse({"detail": [error.to_json()]}, status_code=422)

    @app.exception_handler(RequestValidationError)
    async def invalid(request: Request, error: RequestValidationError) -> JSONResponse:
        detail = [
            point_to_sim(
                {"loc": list(e.get("loc", ())), "msg": str(e.get("msg", "")), "type": e.get("type")}
            )
            for e in error.errors()
        ]
        return JSONResponse({"detail": not_json(request, detail) or detail}, status_code=422)

    @app.exception_handler(OperationalError)
    @app.exception_handler(InterfaceError)
    async def database_away(_request: Request, error: Exception) -> JSONResponse:
        log.warning("database unavailable: %s", type(error).__name__)
        return JSONResponse({"detail": "database unavailable, try again"}, status_code=503)

    @app.exception_handler(StarletteHTTPException)
    async def http_error(request: Request, error: StarletteHTTPException) -> Any:
        if error.status_code == 405:  # Starlette lists only the first matching route's methods
            allowed = _allowed_methods(request.app, request.url.path)
            error.headers = {**(error.headers or {}), "Allow": ", ".join(allowed)}
        return await http_exception_handler(request, error)

    @app.exception_handler(Exception)
    async def internal(_request: Request, error: Exception) -> JSONResponse:
        log.exception("unhandled error")
        return JSONResponse({"detail": "internal server error"}, status_code=500)


def not_json(request: Request, detail: list[dict[str, Any]]) -> list[dict[str, Any]] | None:
    """A body refused whole that was not sent as JSON (a form, text, no Content-Type): say what
    to send instead of pydantic's "a valid dictionary" (a client forgot the header), or None."""
    given = request.headers.get("content-type", "")
    media = given.split(";")[0].strip().lower()
    if media == "application/json" or media.endswith("+json"):
        return None
    if not any(d["loc"] == ["body"] for d in detail):
        return None
    got = f"Content-Type {given!r}" if given else "no Content-Type"
    message = f"the body must be a JSON object sent with Content-Type: application/json ({got})"
    return [{"loc": ["body"], "msg": message, "type": "content_type"}]


def _allowed_methods(app: FastAPI, path: str) -> list[str]:
    """Every method the OpenAPI schema lists for paths matching `path` (the public surface, read
    from the schema because routers nest differently across FastAPI releases)."""
    methods: set[str] = set()
    for template, operations in app.openapi()["paths"].items():
        pattern = re.sub(r"\\{[^/]+?\\}", "[^/]+", re.escape(template))
        if re.fullmatch(pattern, path):
            methods.update(method.upper() for method in operations)
    return sorted(methods)
