"""`/runs`: start, list, inspect and cancel runs; their curves, individuals and best robot."""

from __future__ import annotations

import csv
import io
import re
from typing import Annotated, Any, Literal

from fastapi import Body, Path, Query, Request, Response, status
from fastapi.responses import StreamingResponse

from softevo.api import store
from softevo.api.db import Database
from softevo.api.deps import CoordinatorDep, DatabaseDep, SettingsDep, TokenDep
from softevo.api.events import event_stream
from softevo.api.export import FILE_CONTENT, FormatQuery, file_response
from softevo.api.replay import client_address, replay_response
from softevo.api.routes.meta import idle_workers
from softevo.api.routes.runs import router
from softevo.api.schemas import (
    Curve,
    IndividualDetail,
    IndividualPage,
    Message,
    RunCreate,
    RunPage,
    RunProgress,
    RunPublic,
)
from softevo.api.validation import run_config
from softevo.core.config import RunConfig
from softevo.core.robots.genome import Genome
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.search.stats import curve_columns
from softevo.core.status import IndividualStatus, RunStatus

RunId = Annotated[int, Path(ge=1, le=2**31 - 1, description="run id")]
NOT_FOUND: dict[int | str, dict[str, Any]] = {404: {"model": Message}}
#: FastAPI answers 400 to a body it cannot decode (not UTF-8); invalid JSON text is a 422.
BAD_BODY: dict[int | str, dict[str, Any]] = {
    400: {"model": Message, "description": "The body is not JSON"},
    413: {"model": Message, "description": "The body is over SOFTEVO_MAX_BODY_BYTES"},
    429: {"model": Message, "description": "The run queue is full (SOFTEVO_MAX_QUEUED)"},
}


def run_public(db: Database, run: store.RunRecord, problem: str | None = None) -> RunPublic:
    counts = store.progress_counts(db, run.id)
    rate = run.evaluations / run.compute_seconds if run.compute_seconds > 0 else None
    per_generation = run.compute_seconds / run.generations_done if run.generations_done else None
    eta = None
    if RunStatus(run.status).active and per_generation is not None:
        eta = per_generation * (run.generations_total - run.generations_done)
    return RunPublic(
        id=run.id,
        status=run.status,
        problem=problem,
        preset=run.preset,
        seed=run.seed,
        sweep_id=run.sweep_id,
        progress=RunProgress(
            generation=run.generations_done,
            generations=run.generations_total,
            max_simulations=(run.config or {}).get("max_simulations"),
            evaluations=run.evaluations,
            saved=run.saved,
            fitness_saved=sum(n for s, n in counts.items() if s != IndividualStatus.PENDING),
            evaluations_per_second=rate,
            best_fitness=run.best_fitness,
            best_generation=run.best_generation,
            eta_seconds=eta,
        ),
        config=run.config,
        error=run.error,
        created_at=run.created_at,
        started_at=run.started_at,
        finished_at=run.finished_at,
        takeovers=run.takeovers,
    )


@router.post(
    "",
    status_code=status.HTTP_201_CREATED,
    dependencies=[TokenDep],
    responses={**BAD_BODY, 401: {"model": Message}, 403: {"model": Message}},
)
def create_run(
    body: Annotated[RunCreate, Body()],
    db: DatabaseDep,
    settings: SettingsDep,
    coordinator: CoordinatorDep,
    response: Response,
) -> RunPublic:
    """Queue a run: a preset plus any setting to override. 422 names a bad or too-large field."""
    config = run_config(body.model_dump(exclude_unset=True), settings.limits)
    record = store.create_run(db, config, settings.limits.max_queued)
    coordinator.wake()
    response.headers["Location"] = f"/runs/{record.id}"
    return run_public(db, record)


@router.get("")
def list_runs(
    db: DatabaseDep,
    status_: Annotated[
        RunStatus | None,
        Query(alias="status"),
    ] = None,
    offset: Annotated[int, Query(ge=0, le=10**9)] = 0,
    limit: Annotated[int, Query(ge=1, le=200)] = 50,
) -> RunPage:
    """Newest first."""
    records, total = store.list_runs(db, status_, offset, limit)
    return RunPage(
        items=[run_public(db, r) for r in records], total=total, offset=offset, limit=limit
    )


@router.get("/{run_id}", responses=NOT_FOUND)
def get_run(
    run_id: RunId, db: DatabaseDep, coordinator: CoordinatorDep, settings: SettingsDep
) -> RunPublic:
    """Status and progress: generation g of G, evaluations, rate, best fitness, ETA, and why an
    active run does not progress when this server cannot write its database."""
    run = store.get_run(db, run_id)
    problem = None
    if RunStatus(run.status).active:
        fault, workers = coordinator.faults.current, idle_workers(coordinator, settings)
        if fault is not None:
            problem = f"the database cannot be written: {fault}"
        elif workers not in (None, "ok"):
            problem = workers
    return run_public(db, run, problem)


@router.post(
    "/{run_id}/cancel",
    dependencies=[TokenDep],
    responses={**NOT_FOUND, 409: {"model": Message}, 401: {"model": Message}},
)
def cancel_run(run_id: RunId, db: DatabaseDep, coordinator: CoordinatorDep) -> RunPublic:
    """Stop a queued or running run at once; the results so far are kept. 409 otherwise."""
    record = store.cancel_run(db, run_id)
    coordinator.cancel(run_id)
    return run_public(db, record)


def _csv(rows: list[dict[str, Any]]) -> str:
    first = rows[0] if rows else {}
    columns = curve_columns("coverage" in first, "front_size" in first)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        # .get: a generation committed before a column existed has none of it
        writer.writerow(["" if row.get(c) is None else repr(row[c]) for c in columns])
    return buffer.getvalue()


@router.get(
    "/{run_id}/curve",
    # the model documents the JSON rows (their Pareto columns included) in the OpenAPI schema
    responses={**NOT_FOUND, 200: {"model": Curve, "content": {"text/csv": {}}}},
    response_model_exclude_unset=True,  # coverage, qd_score, the Pareto columns: some runs
)
def get_curve(
    run_id: RunId,
    db: DatabaseDep,
    format: Annotated[Literal["json", "csv"], Query()] = "json",
) -> Any:
    """One row per committed generation: best, mean, median, min, best so far, diversity, ...
    (and coverage, qd_score for a run with descriptors; hypervolume, front_size and
    normalised_hypervolume, 0-1, for a run with objectives)."""
    store.get_run(db, run_id)
    rows = store.curve(db, run_id)
    if format == "csv":
        return Response(
            _csv(rows),
            media_type="text/csv",
            headers={"Content-Disposition": f'attachment; filename="run-{run_id}-curve.csv"'},
        )
    return Curve(run_id=run_id, generations=rows)


@router.get("/{run_id}/individuals", responses=NOT_FOUND)
def list_individuals(
    run_id: RunId,
    db: DatabaseDep,
    generation: Annotated[int | None, Query(ge=0, le=10**6)] = None,
    offset: Annotated[int, Query(ge=0, le=10**9)] = 0,
    limit: Annotated[int, Query(ge=1, le=5000)] = 1000,
) -> IndividualPage:
    """Every individual's fitness by generation (the population dot plot), paginated."""
    run = store.get_run(db, run_id)
    items, total = store.list_individuals(db, run, generation, offset, limit)
    return IndividualPage(
        run_id=run_id,
        items=items,
        total=total,
        offset=offset,
        limit=limit,
    )


@router.get(
    "/{run_id}/individuals/{number}",
    response_model=IndividualDetail,
    responses={**NOT_FOUND, **FILE_CONTENT},
)
def get_individual(
    run_id: RunId,
    number: Annotated[int, Path(ge=0, le=2**31 - 1, description="generation * P + index")],
    db: DatabaseDep,
    format: FormatQuery = None,
) -> Any:
    """One individual with its genome and robot file; with `format`, its robot as that file."""
    run = store.get_run(db, run_id)
    data = store.get_individual(db, run, number)
    config = RunConfig.model_validate(run.config)
    robot = config.make_encoding().to_robot(Genome.from_json(data["genome"]), config.sim)
    if format is not None:
        return file_response(robot, format, f"run-{run_id}-individual-{number}")
    return IndividualDetail(**data, robot=robot_to_json(robot))


def best_robot(db: Database, run_id: int) -> Any:
    run = store.get_run(db, run_id)
    best = store.best_individual(db, run)
    if best is None:
        raise store.NotFoundError(f"run {run_id} has no evaluated generation yet")
    config = RunConfig.model_validate(run.config)
    return config.make_encoding().to_robot(Genome.from_json(best["genome"]), config.sim), best


@router.get(
    "/{run_id}/best", response_model=dict[str, Any], responses={**NOT_FOUND, **FILE_CONTENT}
)
def get_best(run_id: RunId, db: DatabaseDep, format: FormatQuery = None) -> Any:
    """The fastest robot so far as a robot file (softevo.robot/1); with `format`, as that file
    (vxa, glb or stl: docs/export.md)."""
    robot, _best = best_robot(db, run_id)
    if format is not None:
        return file_response(robot, format, f"run-{run_id}-best")
    return robot_to_json(robot)


@router.get("/{run_id}/best/replay", responses=NOT_FOUND)
def get_replay(
    run_id: RunId,
    db: DatabaseDep,
    request: Request,
    fps: Annotated[float, Query(ge=0.1, le=120)] = 30.0,
) -> Response:
    """Frames of mass positions (and the springs) of the best robot, for a 3D viewer (one
    simulated at a time per client: 503 for a second while the first is)."""
    robot, best = best_robot(db, run_id)
    return replay_response(
        robot,
        fps,
        client_address(request),
        run_id=run_id,
        fitness=best["fitness"],
        generation=best["generation"],
    )


_EVENT_ID = re.compile(r"-?[0-9]{1,10}")


def last_event_id(header: str | None) -> int:
    """The generation a reconnecting client saw last; anything but a plain integer of at most
    ten digits (garbage, `--5`, a superscript digit, thousands of digits) means none: -1."""
    if header is None or not _EVENT_ID.fullmatch(header):
        return -1
    return max(-1, int(header))


@router.get(
    "/{run_id}/events",
    responses={**NOT_FOUND, 200: {"content": {"text/event-stream": {}}}},
    response_class=StreamingResponse,
)
def get_events(run_id: RunId, db: DatabaseDep, request: Request) -> StreamingResponse:
    """Server-sent events: `generation` per committed generation, then `end` with the run
    (503 when the server already follows SOFTEVO_MAX_EVENT_CLIENTS streams)."""
    store.get_run(db, run_id)
    watches = request.app.state.watches
    watches.check_room()
    after = last_event_id(request.headers.get("last-event-id"))
    return StreamingResponse(
        event_stream(request, watches, run_id, after, lambda r: run_public(db, r)),
        media_type="text/event-stream",
        headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"},
    )
