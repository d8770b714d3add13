"""The search settings shared by every strategy (`SearchSettings`): plain validated data that
the strategies read, in a module that knows no strategy, so `strategy` imports it and the
registry (which loads strategies) need not be imported by it."""

from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    SerializerFunctionWrapHandler,
    field_validator,
    model_serializer,
    model_validator,
)

from softevo.core.limits import MAX_ARCHIVE_CELLS, MAX_DESCRIPTORS
from softevo.core.search.descriptors import CATALOGUE
from softevo.core.search.vectors import ObjectiveSpec, parse_objectives


class SearchSettings(BaseModel):
    """The search settings every run has, read by the strategies (each lists those it reads in
    `uses`); defaults are the paper's phase 3 (`paper-voxel`). Which strategy is named and
    whether it takes these settings is checked by `StrategySettings`, beside the registry."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True, allow_inf_nan=False)

    algorithm: str = Field(
        "ga",
        max_length=100,
        description="the search strategy, by name: one installed in the entry-point group "
        "`softevo.strategies` (built in: ga, the paper's genetic algorithm; random, random "
        "search; hillclimb, a (1+lambda) hill climber; map-elites, quality-diversity; "
        "nsga2, NSGA-II; afpo, age-fitness Pareto optimisation; steady-state, asynchronous "
        "evolution told in birth order). "
        "GET /algorithms lists those installed, with the settings each one reads.",
    )
    options: dict[str, Any] = Field(
        default_factory=dict,
        description="the strategy's own settings, validated by it (GET /algorithms shows "
        "each strategy's fields); none for the built-ins",
    )
    objectives: tuple[ObjectiveSpec, ...] = Field(
        (),
        description="several objectives at once, by measure name (softevo.core.objectives."
        'MEASURES): ["speed", "-cost_of_transport"], a leading "-" minimising, or objects '
        '{"measure": ..., "goal": "min", "reference": ..., "ideal": ...}; stored as objects '
        "with the hypervolume reference and ideal points filled in. nsga2 and afpo select on "
        "them; any other algorithm keeps the front beside it (curve columns hypervolume, "
        "front_size, normalised_hypervolume). The fitness stays `objective`'s",
    )
    descriptors: tuple[str, ...] = Field(
        (),
        description="quality-diversity descriptors (softevo.core.search.descriptors: voxels, "
        "actuated, soft, height from the body; heading, in degrees, measured by the "
        "simulation); required by map-elites, and with any other algorithm an "
        "archive is kept beside it for comparison",
    )
    bins: tuple[int, ...] = Field((), description="cells along each descriptor's range")
    population: int = Field(25, ge=2, le=10_000)
    generations: int = Field(100, ge=1, le=100_000)
    selection: Literal["grouped", "tournament", "roulette"] = "grouped"
    groups: int = Field(5, ge=1, le=1000, description="groups of grouped truncation")
    survival: float = Field(0.5, gt=0, le=1, description="fraction kept per group")
    tournament_size: int = Field(3, ge=1, le=100)
    crossover_probability: float = Field(1.0, ge=0, le=1)
    mutation_probability: float = Field(0.02, ge=0, le=1, description="fraction of children")
    mutation_genes: int = Field(2, ge=0, le=100_000, description="discrete genes per mutation")
    mutation_sigma: float = Field(0.1, ge=0, le=10, description="real-gene step / range")
    immigrants: float = Field(0.12, ge=0, le=1, description="fraction of P, each generation")
    elitism: bool = True

    @field_validator("objectives", mode="before")
    @classmethod
    def _objectives(cls, value: Any) -> Any:
        return parse_objectives(value)

    @field_validator("descriptors", "bins", mode="before")
    @classmethod
    def _tuple(cls, value: Any) -> Any:
        return tuple(value) if isinstance(value, list) else value

    @model_validator(mode="after")
    def _archive(self) -> SearchSettings:
        self.check_archive()
        return self

    def check_archive(self) -> None:
        """Descriptors known, once each, and one count of bins each, not too many cells."""
        unknown = [name for name in self.descriptors if name not in CATALOGUE]
        if unknown:
            raise ValueError(f"descriptors: unknown {unknown} (known: {', '.join(CATALOGUE)})")
        if len(set(self.descriptors)) != len(self.descriptors):
            raise ValueError(f"descriptors: each at most once, got {list(self.descriptors)}")
        if len(self.descriptors) > MAX_DESCRIPTORS:
            raise ValueError(f"descriptors: at most {MAX_DESCRIPTORS}, got {len(self.descriptors)}")
        if len(self.bins) != len(self.descriptors):
            raise ValueError(
                f"bins: one count per descriptor, got {len(self.bins)} for "
                f"{len(self.descriptors)} descriptors"
            )
        if any(b < 1 for b in self.bins) or math.prod(self.bins) > MAX_ARCHIVE_CELLS:
            raise ValueError(
                f"bins: each at least 1 and at most {MAX_ARCHIVE_CELLS} cells in all, got "
                f"{list(self.bins)} ({math.prod(self.bins)} cells)"
            )

    @model_serializer(mode="wrap")
    def _without_empty_options(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        """A config without options, objectives or a simulation budget (a run config's
        `max_simulations`) dumps as it did before they existed, so the hashes of every
        existing config (output folders, stored runs) stay the same."""
        dumped = handler(self)
        for name in ("options", "objectives", "max_simulations"):
            if not dumped.get(name):
                dumped.pop(name, None)
        return dumped

    @property
    def n_immigrants(self) -> int:
        return math.floor(self.immigrants * self.population + 0.5)
