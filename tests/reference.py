"""The undisturbed reference run that the service, crash and fault tests compare curves with:
the run in process, serially. Computed once per request in a test process (several tests of a
file compare their runs of the same request with it); callers only read it."""

from __future__ import annotations

import json
from collections.abc import Iterable
from functools import cache
from typing import Any

import numpy as np

from softevo.core.config import resolve
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.front import Row, front_rows, front_values


@cache
def _undisturbed(request_text: str) -> Evolution:
    evolution = Evolution.start(resolve(json.loads(request_text)))
    evolution.run(SerialEvaluator())
    return evolution


def undisturbed(request: dict[str, Any]) -> Evolution:
    """The finished in-process run of `request` (a run request, as `POST /runs` takes it)."""
    return _undisturbed(json.dumps(request, sort_keys=True))


def front_points(request: dict[str, Any], rows: Iterable[Row]) -> list[list[float]]:
    """The distinct maximised points of the front of `rows` (individuals as the store or the
    API gives them) under the request's objectives, sorted as the state keeps its front so far
    (`StrategyState.data["front"]`), so a served front compares with the undisturbed run's."""
    specs = resolve(request).objectives
    points = front_values(specs, front_rows(specs, rows))
    return np.unique(points, axis=0).tolist()
