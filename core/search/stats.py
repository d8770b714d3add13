"""Per-generation statistics: the learning curve's rows.

Diversity is the encoding's reading of how much a generation differs (`Encoding.diversity`: by
default `softevo.core.robots.genome.gene_diversity`, the mean pairwise normalised Hamming
distance of the discrete genes; `cppn`, the connections its networks share).
Failed evaluations (NaN) are left out of best/mean/median/min/std and counted in `failed`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from softevo.core.nulls import from_null, to_null

#: The learning-curve columns of the public contract, in order.
CURVE_COLUMNS = (
    "generation",
    "best",
    "mean",
    "median",
    "min",
    "best_so_far",
    "diversity",
    "evaluations",
    "saved",
    "failed",
    "std",
)


#: The columns a run with an archive adds (quality-diversity, `softevo.core.search.archive`).
QD_COLUMNS = ("coverage", "qd_score")

#: The columns a run with `objectives` adds: the hypervolume of the non-dominated set of every
#: individual evaluated so far (against the run's reference point), how many distinct points
#: that set holds, and its normalised hypervolume (0-1, each objective scaled from its reference
#: to its ideal, so every objective weighs the same; `softevo.core.search.vectors`,
#: docs/evolution.md). A generation committed before the last column existed has none.
PARETO_COLUMNS = ("hypervolume", "front_size", "normalised_hypervolume")


def curve_columns(descriptors: bool, objectives: bool) -> tuple[str, ...]:
    """The curve's columns of a run with (or without) descriptors and objectives."""
    return (
        CURVE_COLUMNS + (QD_COLUMNS if descriptors else ()) + (PARETO_COLUMNS if objectives else ())
    )


#: Columns only some runs have: absent (not null) from a row that does not fill them.
_OPTIONAL = frozenset(QD_COLUMNS + PARETO_COLUMNS)


@dataclass(frozen=True)
class GenerationStats:
    generation: int
    best: float
    mean: float
    median: float
    min: float
    std: float
    best_so_far: float
    diversity: float
    size: int
    failed: int
    evaluations: int = 0  # simulations run for this generation
    saved: int = 0  # individuals whose fitness came from the cache
    coverage: float | None = None  # runs with descriptors: filled fraction of the archive
    qd_score: float | None = None  # and the sum of its elites' fitness
    hypervolume: float | None = None  # runs with objectives: of the front so far
    front_size: int | None = None  # and its distinct points
    normalised_hypervolume: float | None = None  # and its volume scaled to the unit box

    def to_json(self) -> dict[str, Any]:
        """JSON; a run without an archive has no coverage or qd_score keys, one without
        objectives no hypervolume, front_size or normalised_hypervolume."""
        values = ((name, getattr(self, name)) for name in _FIELDS)  # all plain numbers
        return {
            k: (to_null(v) if isinstance(v, float) else v)
            for k, v in values
            if v is not None or k not in _OPTIONAL
        }

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> GenerationStats:
        values: dict[str, Any] = {k: (from_null(v) if v is None else v) for k, v in data.items()}
        return cls(**values)


_FIELDS = tuple(field.name for field in fields(GenerationStats))


def generation_stats(
    generation: int,
    fitness: np.ndarray,
    diversity: float,
    best_so_far: float,
    evaluations: int = 0,
    saved: int = 0,
) -> GenerationStats:
    finite = fitness[np.isfinite(fitness)]
    has = len(finite) > 0
    return GenerationStats(
        generation=generation,
        best=float(finite.max()) if has else math.nan,
        mean=float(finite.mean()) if has else math.nan,
        median=float(np.median(finite)) if has else math.nan,
        min=float(finite.min()) if has else math.nan,
        std=float(finite.std()) if has else math.nan,
        best_so_far=best_so_far,
        diversity=diversity,
        size=len(fitness),
        failed=int(len(fitness) - len(finite)),
        evaluations=evaluations,
        saved=saved,
    )
