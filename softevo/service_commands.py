"""`softevo serve`, `softevo worker` and `softevo db upgrade`: the service's commands."""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import signal
import threading
from collections.abc import Iterator
from types import FrameType
from typing import Any

from softevo.command_error import CommandError

#: What `pip install softevo` leaves out: pyproject's `service` extra.
SERVICE_EXTRA = "pip install 'softevo[service]'"


def need_service(modules: tuple[str, ...]) -> str | None:
    """The line to say when a command needs service packages that are not installed (the CLI
    alone is `pip install softevo`), or None when they are all there."""
    missing = [name for name in modules if importlib.util.find_spec(name) is None]
    if not missing:
        return None
    return f"the service's packages are not installed ({', '.join(missing)}): {SERVICE_EXTRA}"


def _need(*modules: str) -> None:
    said = need_service(modules)
    if said is not None:
        raise CommandError(said)


def add_parsers(commands: Any) -> None:
    _serve_parser(commands)
    _worker_parser(commands)
    _db_parser(commands)


def _serve_parser(commands: Any) -> None:
    serve = commands.add_parser(
        "serve",
        help="serve the REST API and drive runs (SQLite + in-process pool by default)",
        description=(
            "Serve the REST API (OpenAPI at /docs) and drive queued runs in this process. "
            "Settings come from the environment: SOFTEVO_DATABASE_URL (default "
            "sqlite:///softevo.db in the working directory, migrated on start), "
            "SOFTEVO_REDIS_URL, SOFTEVO_API_TOKEN, SOFTEVO_MAX_RUNNING, SOFTEVO_WORKERS; "
            "see the README."
        ),
    )
    serve.add_argument("--host", default="127.0.0.1", help="address to bind (127.0.0.1)")
    serve.add_argument("--port", type=int, default=8000, help="port (8000)")
    serve.add_argument("--log-level", default="info", choices=["debug", "info", "warning", "error"])
    serve.add_argument(
        "--migrate",
        action="store_true",
        help="apply the database migrations first (as `softevo db upgrade`), then serve",
    )
    serve.set_defaults(handler=serve_command)


def _worker_parser(commands: Any) -> None:
    worker = commands.add_parser(
        "worker",
        help="evaluate robots for the service: an RQ worker on SOFTEVO_REDIS_URL",
        description=(
            "Start an RQ worker that loads the physics kernels first, then evaluates batches of "
            "robots for every softevo API that shares its Redis (SOFTEVO_REDIS_URL, or --url). "
            "Start as many as there are cores, on any machine that reaches that Redis."
        ),
    )
    worker.add_argument("--url", help="Redis URL (default: SOFTEVO_REDIS_URL)")
    worker.add_argument("--burst", action="store_true", help="exit once the queue is empty")
    worker.add_argument("--name", help="worker name (default: host.pid.random)")
    worker.add_argument(
        "--worker-class",
        choices=["fork", "simple"],
        default="fork",
        help="fork (default): each job in a child of the warm worker, killed if it runs away; "
        "simple: in the worker itself, no fork per job (about 5 ms of RQ's work a job instead "
        "of 20); a job past twice its timeout (a minute past at most) fails and the worker "
        "restarts in place",
    )
    worker.add_argument(
        "--log-level", default="info", choices=["debug", "info", "warning", "error"]
    )
    worker.add_argument(
        "--allow-function",
        action="append",
        default=[],
        metavar="MODULE.FUNCTION",
        help="also run jobs of this function (tests, extensions; repeatable). By default a worker "
        "runs softevo's own jobs only and refuses any other function or callback",
    )
    worker.set_defaults(handler=worker_command)


def _db_parser(commands: Any) -> None:
    db = commands.add_parser(
        "db", help="database maintenance", description="Database maintenance commands."
    )
    db_commands = db.add_subparsers(dest="db_command", required=True, metavar="COMMAND")
    upgrade = db_commands.add_parser(
        "upgrade",
        help="apply the migrations to SOFTEVO_DATABASE_URL",
        description="Apply every Alembic migration to the database of SOFTEVO_DATABASE_URL.",
    )
    upgrade.add_argument("--url", help="database URL (default: SOFTEVO_DATABASE_URL)")
    upgrade.set_defaults(handler=upgrade_command)


def _settings(args: argparse.Namespace) -> Any:
    from softevo.api.settings import Settings

    try:
        return Settings.from_env()
    except ValueError as error:
        args.parser.error(str(error))


def serve_command(args: argparse.Namespace) -> int:
    import logging
    import os

    redis = ("redis", "rq") if os.environ.get("SOFTEVO_REDIS_URL") else ()
    _need("fastapi", "uvicorn", *redis)
    import uvicorn

    from softevo.api.app import create_app
    from softevo.api.server import uvicorn_options

    if not 0 < args.port < 65536:
        args.parser.error(f"--port must be between 1 and 65535, got {args.port}")
    _port_free(args.host, args.port)
    settings = _settings(args)
    if args.migrate:
        upgrade_command(argparse.Namespace(url=settings.database_url, parser=args.parser))
    else:
        _check_migrated(settings.database_url)
    logging.basicConfig(level=args.log_level.upper(), format="%(levelname)s %(name)s: %(message)s")
    with exit_on_sigterm():
        uvicorn.run(
            create_app(settings),
            host=args.host,
            port=args.port,
            log_level=args.log_level,
            **uvicorn_options(settings),
        )
    return 0


def _stop(signum: int, frame: FrameType | None) -> None:
    raise SystemExit(128 + signum)


@contextlib.contextmanager
def exit_on_sigterm() -> Iterator[None]:
    """SIGTERM ends the process as a normal exit with code 143, so its exit handlers run.
    uvicorn shuts down gracefully on SIGTERM and then raises it again under the handler it found:
    Python's default kills the process before multiprocessing's finalizer removes its
    temporary folder (the pool's fork server socket, /tmp/pymp-*), one left per stopped server."""
    if threading.current_thread() is not threading.main_thread():  # signals: the main thread's
        yield
        return
    previous = signal.signal(signal.SIGTERM, _stop)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _check_migrated(url: str) -> None:
    """A PostgreSQL database that is not at the latest migration: one line before uvicorn
    starts (its failed start-up would print the lifespan's whole traceback first). SQLite is
    migrated on start; a database that cannot be reached is left to the start-up to report."""
    from sqlalchemy.exc import SQLAlchemyError

    from softevo.api.app import DatabaseNotMigratedError, check_migrated
    from softevo.api.db import Database

    db = Database(url)
    try:
        if not db.is_sqlite:
            check_migrated(db)
    except DatabaseNotMigratedError as error:
        raise CommandError(str(error)) from None
    except SQLAlchemyError:
        pass
    finally:
        db.engine.dispose()


def _port_free(host: str, port: int) -> None:
    """Fail in one line before migrating or starting anything if the address is taken (uvicorn
    would only find out after start-up, in a screenful of log). Bound as uvicorn binds."""
    import socket

    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
        family, kind, proto, _, address = infos[0]
        with socket.socket(family, kind, proto) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            probe.bind(address)
    except OSError as error:
        reason = error.strerror or str(error)
        raise CommandError(f"cannot listen on {host}:{port} ({reason})") from None


def upgrade_command(args: argparse.Namespace) -> int:
    from sqlalchemy.engine import make_url
    from sqlalchemy.exc import SQLAlchemyError

    from softevo.api.db import Database, current_revision, normalise_url

    url = args.url or _settings(args).database_url
    try:
        db = Database(url)
        db.upgrade()
        revision = current_revision(db.engine)
        db.dispose()
    except (SQLAlchemyError, ValueError) as error:
        shown = make_url(normalise_url(url)).render_as_string(hide_password=True)
        raise CommandError(f"{shown}: {str(error).splitlines()[0]}") from None
    print(f"database at migration {revision}")
    return 0


def worker_command(args: argparse.Namespace) -> int:
    import logging

    _need("redis", "rq")

    from redis.exceptions import RedisError

    from softevo.worker.process import run_worker
    from softevo.worker.queue import redacted

    url = args.url or _settings(args).redis_url
    if not url:
        raise CommandError("no Redis to work for: set SOFTEVO_REDIS_URL or give --url")
    logging.basicConfig(level=args.log_level.upper(), format="%(levelname)s %(name)s: %(message)s")
    try:
        run_worker(
            url,
            burst=args.burst,
            name=args.name,
            worker_class=args.worker_class,
            log_level=args.log_level.upper(),
            allow=tuple(args.allow_function),
        )
    except (RedisError, ValueError) as error:
        raise CommandError(f"{redacted(url)}: {str(error).splitlines()[0]}") from None
    return 0
