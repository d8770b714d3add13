"""The undisturbed reference run that the service, crash and fault tests compare curves with:
the run in process, serially. Computed once per request in a test process (several tests of a
file compare their runs of the same request with it); callers only read it."""

from __future__ import annotations

import json
from functools import cache
from typing import Any

from softevo.core.config import resolve
from softevo.core.evaluation import SerialEvaluator
from softevo.core.evolution import Evolution


@cache
def _undisturbed(request_text: str) -> Evolution:
    evolution = Evolution.start(resolve(json.loads(request_text)))
    evolution.run(SerialEvaluator())
    return evolution


def undisturbed(request: dict[str, Any]) -> Evolution:
    """The finished in-process run of `request` (a run request, as `POST /runs` takes it)."""
    return _undisturbed(json.dumps(request, sort_keys=True))
