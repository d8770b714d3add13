"""Several objectives: the run setting `objectives` and the maximised vectors Pareto code reads.

`"objectives": ["speed", "-cost_of_transport"]` names measures of the simulation's record
(`softevo.core.objectives.MEASURES`); a leading `-` minimises. The object form
`{"measure": "cost_of_transport", "goal": "min", "reference": 50000, "ideal": 0}` says the same
and may set the hypervolume reference point and the ideal point (in the measure's own units):
the normalised hypervolume scales each objective from its reference (0) to its ideal (1). A
config stores each objective in the object form with both filled in, so the bounds a run's
hypervolumes were measured against are kept with the run. Every vector is maximised
(`softevo.core.search.pareto`): a minimised measure enters negated, and so do its bounds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from softevo.core.objectives import ENERGY_MEASURES, MEASURES

#: Most objectives of a run (the exact hypervolume grows as N^(M-1)).
MAX_OBJECTIVES = 4


class ObjectiveSpec(BaseModel):
    """One objective: a measure of the record, whether to maximise or minimise it, and the
    hypervolume reference and ideal points' values for it."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)

    measure: str = Field(description="a measure of the simulation's record (docs/physics.md)")
    goal: Literal["max", "min"] = "max"
    reference: float = Field(
        description="hypervolume reference, in the measure's units: worse than any robot counted"
    )
    ideal: float = Field(
        description="the normalised hypervolume's 1, in the measure's units: better than the "
        "reference (values past it count as it)"
    )

    @property
    def sign(self) -> float:
        return 1.0 if self.goal == "max" else -1.0

    @property
    def label(self) -> str:
        """`-cost_of_transport`-style name (the short form)."""
        return self.measure if self.goal == "max" else f"-{self.measure}"


def parse_objectives(value: Any) -> tuple[ObjectiveSpec, ...]:
    """The `objectives` setting from names or objects; ValueError in one line naming the item."""
    if isinstance(value, str) or not isinstance(value, list | tuple):
        raise ValueError(f"a list of measure names or objects, got {value!r}")
    if len(value) > MAX_OBJECTIVES:
        raise ValueError(f"at most {MAX_OBJECTIVES} objectives, got {len(value)}")
    specs = tuple(_spec(item, position) for position, item in enumerate(value))
    measures = [spec.measure for spec in specs]
    if len(set(measures)) != len(measures):
        raise ValueError(f"each measure at most once, got {measures}")
    return specs


def _spec(item: Any, position: int) -> ObjectiveSpec:
    where = f"item {position}"
    if isinstance(item, ObjectiveSpec):
        return item
    if isinstance(item, str):
        item = {"measure": item[1:], "goal": "min"} if item.startswith("-") else {"measure": item}
    if not isinstance(item, dict):
        raise ValueError(f"{where}: a measure name or an object, got {item!r}")
    unknown = sorted(set(item) - {"measure", "goal", "reference", "ideal"})
    if unknown:
        raise ValueError(f"{where}: unknown key {unknown[0]!r} (measure, goal, reference, ideal)")
    named = item.get("measure")
    if named not in MEASURES:
        raise ValueError(f"{where}: unknown measure {named!r} (measures: {', '.join(MEASURES)})")
    measure: str = named
    given = item.get("goal") or "max"
    if given not in ("max", "min"):
        raise ValueError(f"{where}: goal must be 'max' or 'min', got {given!r}")
    goal: Literal["max", "min"] = "min" if given == "min" else "max"
    reference = _bound(item, "reference", MEASURES[measure][2], where)
    if reference is None:
        raise ValueError(f"{where}: {measure} has no default reference point, give `reference`")
    sign = 1.0 if goal == "max" else -1.0
    ideal = _bound(item, "ideal", None, where)
    if ideal is None:
        ideal = _default_ideal(measure, sign, reference, where)
    elif sign * (ideal - reference) <= 0:
        better = "above" if goal == "max" else "below"
        raise ValueError(
            f"{where}: ideal must be better than the reference ({better} {reference:g}), "
            f"got {ideal!r}"
        )
    return ObjectiveSpec(measure=measure, goal=goal, reference=reference, ideal=ideal)


def _bound(item: dict[str, Any], key: str, default: float | None, where: str) -> float | None:
    """`reference` or `ideal` of an object, a finite number (absent or null: `default`)."""
    value = item.get(key)
    if value is None:
        return default
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{where}: {key} must be a number, got {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"{where}: {key} must be finite, got {value!r}")
    return float(value)


def _default_ideal(measure: str, sign: float, reference: float, where: str) -> float:
    """The measure's ideal (`MEASURES`), or, for a reference given at or past it (a config may
    have been stored before ideals existed), one default range (or 1 unit) past the reference:
    every config that loaded before still loads."""
    _, _, default_reference, ideal = MEASURES[measure]
    if sign * (ideal - reference) > 0:
        return ideal
    span = abs(ideal - default_reference) if default_reference is not None else 1.0
    shifted = reference + sign * span
    if shifted == reference:  # a reference so large that the span is below its precision
        shifted = math.nextafter(reference, sign * math.inf)
    if not math.isfinite(shifted):
        raise ValueError(f"{where}: no ideal is better than reference {reference!r}, give `ideal`")
    return shifted


def needs_energy(specs: Sequence[ObjectiveSpec]) -> bool:
    """Whether these objectives read a measure of the actuators' work."""
    return any(spec.measure in ENERGY_MEASURES for spec in specs)


def reference_point(specs: Sequence[ObjectiveSpec]) -> np.ndarray:
    """The hypervolume reference point, maximised ([M])."""
    return np.array([spec.sign * spec.reference for spec in specs], dtype=np.float64)


def ideal_point(specs: Sequence[ObjectiveSpec]) -> np.ndarray:
    """The normalised hypervolume's ideal point, maximised ([M]; the nadir is the reference)."""
    return np.array([spec.sign * spec.ideal for spec in specs], dtype=np.float64)


def objective_values(
    specs: Sequence[ObjectiveSpec],
    records: Sequence[Mapping[str, float | None]],
    fitness: np.ndarray,
) -> np.ndarray:
    """[N, M] maximised objective values of N individuals: each spec's measure from the record,
    negated where minimised. A row is all NaN (failed) where the fitness is NaN or any of its
    measures is missing or not finite; with no specs, the fitness alone ([N, 1])."""
    values = np.asarray(fitness, dtype=np.float64)
    if not specs:
        return values[:, None].copy()
    rows = np.full((len(values), len(specs)), np.nan)
    for i, (record, value) in enumerate(zip(records, values, strict=True)):
        if not math.isfinite(value):
            continue
        row = [_number(record.get(spec.measure)) * spec.sign for spec in specs]
        if all(math.isfinite(x) for x in row):
            rows[i] = row
    return rows


def _number(value: Any) -> float:
    return float(value) if isinstance(value, int | float) else math.nan
