"""Pictures of robots served by the API (README "Moving pictures"): a GIF / MP4 of the best
robot's simulation and a PNG thumbnail of it at rest.

A movie simulates and draws dozens of frames, so it runs in the replays' own processes under
their RUNNING_AT_ONCE bound, one picture at a time and one per client
(`softevo.api.replay.in_own_process`: the API process never loads the physics), within the
service's picture limits (core/limits.py), at a quantised fps and duration, and the last few are
kept.
A thumbnail needs no simulation (the robot at rest, a few milliseconds of drawing): it is drawn
here and kept per (run, best individual), so the runs list costs one drawing per new best.
"""

from __future__ import annotations

import json
import threading
from collections import OrderedDict
from typing import Any

from softevo.api.replay import fps_bucket, in_own_process
from softevo.core.outputs import picture
from softevo.core.robots.robot_file import robot_to_json

#: Movies and thumbnails remembered (the newest).
CACHED_MOVIES = 8
CACHED_THUMBNAILS = 512

_movies: OrderedDict[tuple[str, str, float, float], bytes] = OrderedDict()
_thumbnails: OrderedDict[tuple[int, Any], bytes] = OrderedDict()
_lock = threading.Lock()
#: matplotlib's drawing of one figure is not meant to be shared across threads: one at a time.
_drawing = threading.Lock()


class PictureUnsupportedError(RuntimeError):
    """The picture needs a program this server lacks (ffmpeg for MP4): 501, saying how to fix."""


#: Frame rates a movie is drawn at (a request's fps goes to the nearest in ratio) and the step
#: its duration is rounded to (s): 14.999 and 15 fps, 3 and 3.0001 s, share a movie.
FPS_BUCKETS = (0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 15.0)
SECONDS_STEP = 0.5


def quantise(fps: float, seconds: float) -> tuple[float, float]:
    """The (fps, seconds) a movie asked for is drawn and remembered at."""
    steps = max(1, round(seconds / SECONDS_STEP))
    return fps_bucket(fps, FPS_BUCKETS), steps * SECONDS_STEP


def movie(robot: Any, format: str, fps: float, seconds: float, client: str | None = None) -> bytes:
    """The robot's simulation as GIF / MP4 bytes at `quantise`d settings, remembered by (robot,
    format, fps, seconds); drawn in one of `client`'s picture slots (`softevo.api.replay.slot`)."""
    if format == "mp4" and not picture.ffmpeg_available():
        raise PictureUnsupportedError(picture.FFMPEG_MISSING)
    fps, seconds = quantise(fps, seconds)
    robot_file = robot_to_json(robot)
    key = (json.dumps(robot_file, sort_keys=True), format, fps, seconds)
    with _lock:
        if key in _movies:
            _movies.move_to_end(key)
            return _movies[key]
    data: bytes = in_own_process(
        picture.movie_from_file, robot_file, format, fps, seconds, client=client
    )
    _remember(_movies, key, data, CACHED_MOVIES)
    return data


def thumbnail(run_id: int, best: dict[str, Any], robot: Any) -> bytes:
    """A small PNG of the run's best robot at rest, drawn once per (run, best individual)."""
    key = (run_id, (best.get("id"), best.get("genome_hash")))
    with _lock:
        if key in _thumbnails:
            _thumbnails.move_to_end(key)
            return _thumbnails[key]
    with _drawing:
        data = picture.thumbnail_png(robot)
    _remember(_thumbnails, key, data, CACHED_THUMBNAILS)
    return data


def _remember(cache: OrderedDict, key: Any, data: bytes, size: int) -> None:
    with _lock:
        cache[key] = data
        while len(cache) > size:
            cache.popitem(last=False)
