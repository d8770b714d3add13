"""`/runs/{id}/front`: a run's Pareto front, the robots no other evaluated robot beats in every
objective (issue 36)."""

from __future__ import annotations

from typing import Annotated

from fastapi import Query

from softevo.api import store
from softevo.api.deps import DatabaseDep
from softevo.api.routes.runs import router
from softevo.api.routes.runs.lifecycle import NOT_FOUND, RunId
from softevo.api.schemas import FrontPoint, FrontPublic
from softevo.api.store import front as front_store
from softevo.core.config import RunConfig
from softevo.core.robots.genome import Genome
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.search.front import front_rows


@router.get("/{run_id}/front", responses=NOT_FOUND)
def get_front(
    run_id: RunId,
    db: DatabaseDep,
    robots: Annotated[bool, Query(description="include each point's robot file")] = False,
) -> FrontPublic:
    """The non-dominated set of every individual evaluated so far under the run's `objectives`
    (each genome once, where it first appeared), with its measures, generation and index. A
    failed individual is on no front. 404 for a run without `objectives`."""
    run = store.get_run(db, run_id)
    config = RunConfig.model_validate(run.config)
    if not config.objectives:
        raise store.NotFoundError(f"run {run_id} has no front: it was started without objectives")
    rows = front_rows(config.objectives, front_store.evaluated(db, run_id))
    genomes = {}
    if robots:
        genomes = front_store.genomes(db, run_id, [(r["generation"], r["index"]) for r in rows])
    encoding = config.make_encoding()
    points = [
        FrontPoint(
            generation=row["generation"],
            index=row["index"],
            id=row["generation"] * config.population + row["index"],
            fitness=row["fitness"],
            operator=row["operator"],
            measures=row["measures"],
            robot=robot_to_json(
                encoding.to_robot(
                    Genome.from_json(genomes[(row["generation"], row["index"])]), config.sim
                )
            )
            if robots
            else None,
        )
        for row in rows
    ]
    return FrontPublic(
        run_id=run_id,
        generations=run.generations_done,
        objectives=[spec.model_dump() for spec in config.objectives],
        points=points,
    )
