"""`/sweeps`: one base experiment over many bounding boxes and seeds (the paper's Figure 4a)."""

from __future__ import annotations

import statistics
from typing import Annotated, Any

from fastapi import APIRouter, Body, Path, Response, status

from softevo.api import store
from softevo.api.db import Database
from softevo.api.deps import CoordinatorDep, DatabaseDep, SettingsDep, TokenDep
from softevo.api.routes.runs import BAD_BODY
from softevo.api.schemas import Message, SweepBox, SweepCreate, SweepPublic
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
    sweep, runs = store.get_sweep(db, sweep_id)
    boxes: dict[tuple[int, int, int], list[store.RunRecord]] = {}
    for run in runs:
        boxes.setdefault(tuple(run.config["shape"]), []).append(run)  # type: ignore[arg-type]
    out = []
    for shape, members in boxes.items():
        best = [r.best_fitness for r in members if r.status == RunStatus.COMPLETED]
        best = [b for b in best if b is not None]
        out.append(
            SweepBox(
                shape=shape,
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
    """Queue one run per (bounding box, seed); every config is checked before any is queued."""
    request: dict[str, Any] = body.model_dump(exclude_unset=True, exclude={"shapes", "seeds"})
    shapes, seeds = (
        list(dict.fromkeys(tuple(s) for s in body.shapes)),
        list(dict.fromkeys(body.seeds)),
    )
    if len(shapes) * len(seeds) > settings.limits.max_sweep_runs:
        raise RequestError(["seeds"], f"{len(shapes)} boxes x {len(seeds)} seeds is over the "
                           f"limit of {settings.limits.max_sweep_runs} runs per sweep "
                           "(SOFTEVO_MAX_SWEEP_RUNS)")  # fmt: skip
    configs = []
    for i, shape in enumerate(shapes):
        for seed in seeds:
            configs.append(
                run_config(
                    {**request, "shape": shape, "seed": seed}, settings.limits, ("shapes", str(i))
                )
            )
    check_budget(configs, settings.limits, ["seeds"])  # the sweep's runs together
    stored = body.model_dump(mode="json", exclude_unset=True)
    stored.update(shapes=[list(s) for s in shapes], seeds=seeds)
    sweep_id, _ = store.create_sweep(db, stored, configs, settings.limits.max_queued)
    coordinator.wake()
    response.headers["Location"] = f"/sweeps/{sweep_id}"
    return sweep_public(db, sweep_id)


@router.get("/{sweep_id}", responses={404: {"model": Message}})
def get_sweep(sweep_id: SweepId, db: DatabaseDep) -> SweepPublic:
    """Per box: best speed (mean, spread, min, max over completed seeds) and the run ids."""
    return sweep_public(db, sweep_id)
