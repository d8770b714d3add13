"""What the dashboard and papers look at: a replay of any individual, and the run's figures as PNG.

Both compute on request (a simulation, a matplotlib figure) in the API process, so each is
bounded: a replay by the run's own simulated duration (under SOFTEVO_MAX_DURATION) and the frame
rate cap, a figure by the run's size (under SOFTEVO_MAX_EVALUATIONS individuals), of which it
reads only the columns it draws (the population: generation and fitness, 16 bytes each).
"""

from __future__ import annotations

import io
import threading
from typing import Annotated, Any, Literal

from fastapi import Path, Query, Request, Response

from softevo.api import pictures, store
from softevo.api.deps import DatabaseDep
from softevo.api.replay import client_address, replay_response
from softevo.api.routes.runs import router
from softevo.api.routes.runs.lifecycle import NOT_FOUND, RunId, best_robot
from softevo.api.schemas import Message
from softevo.core.config import RunConfig
from softevo.core.limits import MIN_PICTURE_FPS, SERVICE_PICTURE_FPS, SERVICE_PICTURE_SECONDS
from softevo.core.outputs.picture import FPS, MEDIA_TYPES, SECONDS
from softevo.core.robots.genome import Genome

#: pyplot keeps global state (its figure registry, rcParams): one figure at a time in this process
_FIGURES = threading.Lock()

Fps = Annotated[float, Query(ge=0.1, le=120, description="frames per simulated second")]


@router.get("/{run_id}/individuals/{number}/replay", responses=NOT_FOUND)
def get_individual_replay(
    run_id: RunId,
    number: Annotated[int, Path(ge=0, le=2**31 - 1, description="generation * P + index")],
    db: DatabaseDep,
    request: Request,
    fps: Fps = 30.0,
) -> Response:
    """Frames of mass positions (and the springs) of individual `number`, for a 3D viewer."""
    run = store.get_run(db, run_id)
    data = store.get_individual(db, run, number)
    config = RunConfig.model_validate(run.config)
    robot = config.make_encoding().to_robot(Genome.from_json(data["genome"]), config.sim)
    return replay_response(
        robot,
        fps,
        client_address(request),
        run_id=run_id,
        number=number,
        generation=data["generation"],
        fitness=data["fitness"],
    )


@router.get(
    "/{run_id}/figures/{kind}.png",
    responses={**NOT_FOUND, 200: {"content": {"image/png": {}}}},
    response_class=Response,
)
def get_figure(
    run_id: RunId, kind: Literal["curve", "population", "diversity"], db: DatabaseDep
) -> Response:
    """The learning curve, population dot plot or diversity chart as a publication PNG."""
    from softevo.core.outputs import figures

    run = store.get_run(db, run_id)
    points = store.population_points(db, run_id) if kind == "population" else None
    rows = store.curve(db, run_id) if kind != "population" else []
    title = figures.run_title(run.config, f"run {run_id}")
    ylabel = figures.fitness_label(run.config)
    buffer = io.BytesIO()
    with _FIGURES:
        if points is not None:
            figure = figures.population_figure(points, f"population: {title}", ylabel)
        elif kind == "curve":
            figure = figures.curve_figure(rows, f"learning curve: {title}", ylabel)
        else:
            figure = figures.diversity_figure(rows, f"diversity: {title}")
        figures.write(figure, buffer)
    return Response(buffer.getvalue(), media_type="image/png")


PictureFps = Annotated[
    float,
    Query(ge=MIN_PICTURE_FPS, le=SERVICE_PICTURE_FPS, description="frames per simulated second"),
]
PictureSeconds = Annotated[
    float, Query(gt=0, le=SERVICE_PICTURE_SECONDS, description="simulated seconds drawn")
]
MOVIE_RESPONSES: dict[int | str, dict[str, Any]] = {
    **NOT_FOUND,
    501: {"model": Message, "description": "MP4 asked for and no ffmpeg on the server"},
    503: {"model": Message, "description": "Too many pictures and replays being made at once"},
}


@router.get(
    "/{run_id}/best/replay.{format}",
    responses={
        **MOVIE_RESPONSES,
        200: {"content": {"image/gif": {}, "video/mp4": {}}, "description": "the movie"},
    },
    response_class=Response,
)
def get_best_movie(
    run_id: RunId,
    format: Literal["gif", "mp4"],
    db: DatabaseDep,
    request: Request,
    fps: PictureFps = FPS,
    duration: PictureSeconds = SECONDS,
) -> Response:
    """The best robot's simulation drawn as shaded voxels, the camera following it: a GIF, or an
    MP4 where the server has ffmpeg (501 otherwise). Drawn on request at the nearest of the frame
    rates 0.5, 1, 2, 3, 4, 5, 6, 8, 10, 12, 15 and the duration rounded to 0.5 s, then
    remembered; one picture is drawn at a time, and one replay or picture per client (503)."""
    robot, _best = best_robot(db, run_id)
    data = pictures.movie(robot, format, fps, duration, client_address(request))
    return Response(data, media_type=MEDIA_TYPES[format])


@router.get(
    "/{run_id}/best/thumbnail.png",
    responses={**NOT_FOUND, 200: {"content": {"image/png": {}}, "description": "the picture"}},
    response_class=Response,
)
def get_best_thumbnail(run_id: RunId, db: DatabaseDep) -> Response:
    """A small shaded picture of the best robot at rest (for the runs list), kept per best."""
    robot, best = best_robot(db, run_id)
    return Response(
        pictures.thumbnail(run_id, best, robot),
        media_type="image/png",
        headers={"Cache-Control": "max-age=60"},
    )
