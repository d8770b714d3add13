"""The NaN <-> null rule, written once: a number that is not finite (a failed robot's speed, the
statistics of a generation where all failed) is `null` in JSON and NULL in the database, and
`null` reads back as NaN. Never 0, which would be a real speed."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import numpy as np


def to_null(value: float | None) -> float | None:
    """A finite number as it is, anything else (NaN, infinities, None) as None."""
    return value if value is not None and math.isfinite(value) else None


def from_null(value: float | None) -> float:
    """None as NaN, a number as a float."""
    return math.nan if value is None else float(value)


def to_nulls(values: Iterable[float]) -> list[float | None]:
    return [to_null(value) for value in values]


def from_nulls(values: Iterable[float | None]) -> np.ndarray:
    return np.array([from_null(value) for value in values], dtype=np.float64)


def to_null_record(record: Mapping[str, float]) -> dict[str, float | None]:
    """A record of measures (name -> value) as JSON keeps it: NaN as None."""
    return {name: value if math.isfinite(value) else None for name, value in record.items()}


class Record(dict[str, float]):
    """A record of measures read from JSON (name -> value, NaN for null) that keeps the JSON text
    the store writes of it, once made (`text`): a genome met again (a survivor, a copy) has its
    record written with every generation it is a member of, and it is this same object each
    time. A record is never changed once read."""

    __slots__ = ("text",)


def from_null_record(record: Mapping[str, float | None] | None) -> dict[str, float]:
    """A record of measures as JSON kept it, None as NaN (a missing record: empty)."""
    if not record:
        return {}
    return Record(
        {name: math.nan if value is None else float(value) for name, value in record.items()}
    )
