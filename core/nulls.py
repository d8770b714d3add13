"""The NaN <-> null rule, written once: a number that is not finite (a failed robot's speed, the
statistics of a generation where all failed) is `null` in JSON and NULL in the database, and
`null` reads back as NaN. Never 0, which would be a real speed."""

from __future__ import annotations

import json
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
    """A record of measures read from JSON (name -> value, NaN for null) that keeps its JSON text
    (`record_text`) once known (`text`): the job sends it beside the record, so the service
    stores it as it came, and a genome met again (a survivor, a copy), whose record is this same
    object every generation, is not encoded again. A record is never changed once read."""

    __slots__ = ("text",)
    text: str


def record_text(record: Mapping[str, float | None]) -> str:
    """A record of measures as JSON text, the one form every copy of it takes (the job's, the
    store's): compact, in the record's order, NaN, infinities and None as null. NaN is replaced
    in the text (a measure's name, an identifier, never holds it) rather than in a copy first."""
    text = _ENCODE(record)
    if "Infinity" in text:  # not a number JSON knows either: the slow, exact way
        return _ENCODE({name: to_null(value) for name, value in record.items()})
    return text.replace("NaN", "null")


#: One encoder for every record (`json.dumps` with options builds one per call).
_ENCODE = json.JSONEncoder(separators=(",", ":")).encode


def from_null_record(record: Mapping[str, float | None] | None) -> dict[str, float]:
    """A record of measures as JSON kept it, None as NaN (a missing record: empty)."""
    if not record:
        return {}
    return Record(
        {name: math.nan if value is None else float(value) for name, value in record.items()}
    )
