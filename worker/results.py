"""A job's result as the API side reads it off the batch's result list: plain JSON of the right
shape, or nothing (`RQEvaluator.collect` then skips it)."""

from __future__ import annotations

import json
from typing import Any

from softevo.core.evaluator import well_formed


def parse_result(raw: bytes | str, robots: int) -> dict[str, Any] | None:
    """A job's result as plain JSON data, or None when it is not one: bytes that are not JSON
    (a pickle, say) are never deserialised any other way, and a result of the wrong shape is
    not taken for fitness."""
    try:
        payload = json.loads(raw, parse_constant=_refuse_constant)
    except (ValueError, UnicodeDecodeError):
        return None
    if not isinstance(payload, dict) or not isinstance(payload.get("worker", ""), str):
        return None
    if "fitness" in payload:
        seconds = payload.get("seconds")
        if not well_formed(payload, robots):
            return None
        if not isinstance(seconds, int | float) or isinstance(seconds, bool) or seconds < 0:
            return None
        return payload
    if isinstance(payload.get("refused"), str):
        return payload
    return payload if isinstance(payload.get("error"), str) else None


def _refuse_constant(name: str) -> Any:
    """NaN and Infinity are not JSON: a failed robot's speed is null."""
    raise ValueError(f"{name} in a result")
