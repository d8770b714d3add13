"""`/runs/{id}/archive`: a quality-diversity run's map, the best robot of every kind of body."""

from __future__ import annotations

from typing import Annotated

from fastapi import Query

from softevo.api import store
from softevo.api.deps import DatabaseDep
from softevo.api.routes.runs import router
from softevo.api.routes.runs.lifecycle import NOT_FOUND, RunId
from softevo.api.schemas import ArchiveCell, ArchivePublic, DescriptorAxis
from softevo.core.config import RunConfig
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.search.archive import Archive
from softevo.core.search.descriptors import CATALOGUE


@router.get("/{run_id}/archive", responses=NOT_FOUND)
def get_archive(
    run_id: RunId,
    db: DatabaseDep,
    robots: Annotated[bool, Query(description="include each elite's robot file")] = False,
) -> ArchivePublic:
    """Every filled cell of the run's archive (descriptor values, fitness, where the elite was
    bred), with coverage and QD-score, as of the last committed generation. 404 for a run
    without `descriptors`."""
    run = store.get_run(db, run_id)
    config = RunConfig.model_validate(run.config)
    if not config.descriptors:
        raise store.NotFoundError(
            f"run {run_id} keeps no archive: it was started without descriptors"
        )
    stored = store.archive(db, run_id)
    archive = Archive.from_json(stored) if stored else Archive(config.descriptors, config.bins)
    encoding = config.make_encoding()
    cells = [
        ArchiveCell(
            cell=list(elite.cell),
            values=list(elite.values),
            fitness=elite.fitness,
            generation=elite.generation,
            index=elite.index,
            id=elite.generation * config.population + elite.index,
            robot=robot_to_json(encoding.to_robot(elite.genome, config.sim)) if robots else None,
        )
        for elite in archive.ordered()
    ]
    axes = [
        DescriptorAxis(
            name=name,
            low=CATALOGUE[name].low,
            high=CATALOGUE[name].high,
            bins=bins,
            help=CATALOGUE[name].help,
        )
        for name, bins in zip(config.descriptors, config.bins, strict=True)
    ]
    return ArchivePublic(
        run_id=run_id,
        generations=run.generations_done,
        descriptors=axes,
        coverage=archive.coverage,
        qd_score=archive.qd_score,
        cells=cells,
    )
