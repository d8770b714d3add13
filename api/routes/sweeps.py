"""`/sweeps`: one base experiment over many bounding boxes and seeds (the paper's Figure 4a), or
over the task presets and seeds (a benchmark suite in one request)."""

from __future__ import annotations

import statistics
from typing import Annotated, Any

from fastapi import APIRouter, Body, Path, Query, Response, status

from softevo.api import store
from softevo.api.db import Database
from softevo.api.deps import CoordinatorDep, DatabaseDep, SettingsDep, TokenDep
from softevo.api.routes.runs.lifecycle import BAD_BODY
from softevo.api.schemas import Message, SweepBox, SweepCreate, SweepPage, SweepPublic
from softevo.api.validation import RequestError, check_budget, run_config
from softevo.core.status import RunStatus

router = APIRouter(prefix="/sweeps", tags=["sweeps"])
SweepId = Annotated[int, Path(ge=1, le=2**31 - 1, description="sweep id")]


def _status(statuses: list[str]) -> str:
    for candidate in (RunStatus.RUNNING, RunStatus.QUEUED, RunStatus.FAILED, RunStatus.CANCELLED):
        if candidate in statuses:
            return candidate
    return RunStatus.COMPLETED


def sweep_public(db: Database, sweep_id: int) -> SweepPublic:
    return _public(*store.get_sweep(db, sweep_id))


def _public(sweep: dict[str, Any], runs: list[store.RunRecord]) -> SweepPublic:
    by_task = bool(sweep["request"].get("tasks"))
    boxes: dict[tuple[str | None, tuple[int, int, int]], list[store.RunRecord]] = {}
    for run in runs:
        key = (run.preset if by_task else None, tuple(run.config["shape"]))
        boxes.setdefault(key, []).append(run)  # type: ignore[arg-type]
    out = []
    for (task, shape), members in boxes.items():
        best = [r.best_fitness for r in members if r.status == RunStatus.COMPLETED]
        best = [b for b in best if b is not None]
        out.append(
            SweepBox(
                shape=shape,
                task=task,
                run_ids=[r.id for r in members],
                statuses=[r.status for r in members],
                completed=sum(r.status == RunStatus.COMPLETED for r in members),
                best_mean=statistics.fmean(best) if best else None,
                best_std=statistics.pstdev(best) if best else None,
                best_min=min(best) if best else None,
                best_max=max(best) if best else None,
            )
        )
    return SweepPublic(
        id=sweep["id"],
        status=_status([r.status for r in runs]),  # type: ignore[arg-type]
        created_at=sweep["created_at"],
        request=sweep["request"],
        boxes=out,
    )


@router.post(
    "",
    status_code=status.HTTP_201_CREATED,
    dependencies=[TokenDep],
    responses={**BAD_BODY, 401: {"model": Message}, 403: {"model": Message}},
)
def create_sweep(
    body: Annotated[SweepCreate, Body()],
    db: DatabaseDep,
    settings: SettingsDep,
    coordinator: CoordinatorDep,
    response: Response,
) -> SweepPublic:
    """Queue one run per (bounding box, seed), or per (task, box, seed) with `tasks`; every
    config is checked before any is queued."""
    given = body.model_fields_set
    request: dict[str, Any] = body.model_dump(
        exclude_unset=True, exclude={"shapes", "seeds", "tasks"}
    )
    if body.tasks and "preset" in given:
        raise RequestError(["preset"], "give tasks or a preset, not both: each task is a preset")
    tasks: list[str | None] = list(dict.fromkeys(body.tasks)) if body.tasks else [None]
    shapes: list[tuple[int, int, int] | None] = (
        list(dict.fromkeys(tuple(s) for s in body.shapes))
        if not body.tasks or "shapes" in given
        else [None]  # each task's own box
    )
    seeds = list(dict.fromkeys(body.seeds))
    count = len(tasks) * len(shapes) * len(seeds)
    if count > settings.limits.max_sweep_runs:
        sizes = f"{len(tasks)} tasks x " if body.tasks else ""
        raise RequestError(
            ["seeds"],
            f"{sizes}{len(shapes)} boxes x {len(seeds)} seeds is over "
            f"the limit of {settings.limits.max_sweep_runs} runs per sweep "
            "(SOFTEVO_MAX_SWEEP_RUNS)",
        )
    configs = []
    for t, task in enumerate(tasks):
        for i, shape in enumerate(shapes):
            where = ("tasks", str(t)) if shape is None else ("shapes", str(i))
            for seed in seeds:
                one = {**request, "seed": seed}
                one.update({} if task is None else {"preset": task})
                one.update({} if shape is None else {"shape": shape})
                configs.append(run_config(one, settings.limits, where))
    check_budget(configs, settings.limits, ["seeds"])  # the sweep's runs together
    stored = body.model_dump(mode="json", exclude_unset=True)
    stored.update(seeds=seeds)
    if shapes != [None]:
        stored.update(shapes=[list(s) for s in shapes if s is not None])
    sweep_id, _ = store.create_sweep(db, stored, configs, settings.limits.max_queued)
    coordinator.wake()
    response.headers["Location"] = f"/sweeps/{sweep_id}"
    return sweep_public(db, sweep_id)


@router.get("")
def list_sweeps(
    db: DatabaseDep,
    offset: Annotated[int, Query(ge=0, le=10**9)] = 0,
    limit: Annotated[int, Query(ge=1, le=200)] = 50,
) -> SweepPage:
    """Newest first, each with its boxes (or tasks) and their runs, as GET /sweeps/{id}."""
    sweeps, total = store.list_sweeps(db, offset, limit)
    return SweepPage(
        items=[_public(*one) for one in sweeps], total=total, offset=offset, limit=limit
    )


@router.get("/{sweep_id}", responses={404: {"model": Message}})
def get_sweep(sweep_id: SweepId, db: DatabaseDep) -> SweepPublic:
    """Per box (and task): best fitness (mean, spread, min, max over completed seeds) and the run
    ids."""
    return sweep_public(db, sweep_id)
