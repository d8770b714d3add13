"""Request and response bodies of the REST API (the OpenAPI schema at /docs is built from these).

`RunCreate` is a preset name plus any setting to override; the merged result is validated by
`softevo.core.config.resolve` (which names the offending field) and then checked against the
service's ceilings (`softevo.api.settings.Limits`).
"""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Any, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, StrictInt, create_model

from softevo.core.config import PAPER_NINE_SHAPES, RunConfig, parse_shape
from softevo.core.limits import MAX_SIDE
from softevo.core.objectives import Objective
from softevo.core.robots.settings import SimSettings
from softevo.core.robots.tasks import TASKS
from softevo.core.robots.terrain import Terrain
from softevo.core.search.configured import StrategySettings
from softevo.core.search.vectors import MAX_OBJECTIVES
from softevo.core.status import IndividualStatus, RunStatus

# Strict numbers in every body: no bool or string for a number, no float for a count.
Side = Annotated[int, Field(ge=1, le=MAX_SIDE, strict=True)]
Shape = tuple[Side, Side, Side]


def _shape_text(value: Any) -> Any:
    """ "5x5x3", as the CLI takes it, refused in the CLI's words; a list is checked as one."""
    return parse_shape(value) if isinstance(value, str) else value


#: A bounding box: [nx, ny, nz], or the CLI's "5x5x3" text.
ShapeIn = Annotated[Shape, BeforeValidator(_shape_text)]
Seed = Annotated[int, Field(ge=0, le=2**63 - 1, strict=True)]
Number = Annotated[float, Field(strict=True)]


def _sim_field(name: str, info: Any) -> Any:
    """A simulation setting as a body field: optional, a strict number with its bounds, the
    physics profile, or the terrain (validated as a terrain alone, so its errors name its own
    fields). A `dt` left out or null is the profile's (derived in `physical`)."""
    if name == "terrain":
        return (Terrain | None, Field(None, description=info.description))
    if name == "profile":
        return (info.annotation | None, Field(None, description=info.description))
    annotation = Annotated[float, *info.metadata, Field(strict=True)]
    return (annotation | None, Field(None, description=info.description))


#: The simulation settings to override (None: the preset's value), bounds in the schema.
SimOverrides = create_model(
    "SimOverrides",
    __config__=ConfigDict(extra="forbid"),
    **{name: _sim_field(name, info) for name, info in SimSettings.model_fields.items()},
)


class _RunSettings(BaseModel):
    model_config = ConfigDict(extra="forbid")

    preset: str = Field("paper-voxel", description="preset whose settings the others override")
    encoding: str | None = Field(
        None,
        max_length=100,
        description="an encoding installed in the entry-point group `softevo.encodings` "
        "(built in: voxel, voxel-phase, cube-springs, spring, cppn)",
    )
    sim: SimOverrides | None = Field(
        None,
        description="simulation settings to override; `terrain` takes an object such as "
        '{"kind": "slope", "angle_deg": 10} (docs/tasks.md)',
    )
    objective: Objective | None = Field(
        None, description="fitness: speed (default), forward, climb or efficiency (docs/tasks.md)"
    )
    cube_options: list[tuple[Number, Number, Number, Number]] | None = Field(
        None, max_length=64, description="the cube's spring options [k, b, w, c] (at most 64)"
    )
    max_simulations: StrictInt | None = Field(
        None,
        ge=1,
        le=10**9,
        description=RunConfig.model_fields["max_simulations"].description,
    )


def _optional(info: Any) -> Any:
    """A GA setting as a body field: optional, its bounds kept, strict if it is a number (and
    counts such as `bins` integers: not true, not 4.0)."""
    strict = [Field(strict=True)] if info.annotation in (int, float, bool) else []
    metadata = [*info.metadata, *strict]
    base = tuple[StrictInt, ...] if info.annotation == tuple[int, ...] else info.annotation
    annotation = Annotated[base, *metadata] if metadata else base
    return (annotation | None, Field(None, description=info.description))


#: Every GA setting, optional (None: the preset's value), with its bounds in the schema.
_GA_FIELDS: dict[str, Any] = {
    name: _optional(info) for name, info in StrategySettings.model_fields.items()
}


class ObjectiveIn(BaseModel):
    """One objective in the object form; the run stores it with its reference and ideal filled
    in."""

    model_config = ConfigDict(extra="forbid")

    measure: str = Field(description="a measure of the simulation's record (docs/physics.md)")
    goal: Literal["max", "min"] = "max"
    reference: float | None = Field(
        None,
        description="hypervolume reference in the measure's units (default: docs/evolution.md)",
    )
    ideal: float | None = Field(
        None,
        description="the normalised hypervolume's 1, in the measure's units, better than the "
        "reference (default: docs/evolution.md)",
    )


_GA_FIELDS["objectives"] = (
    list[str | ObjectiveIn] | None,
    Field(
        None,
        max_length=MAX_OBJECTIVES,
        description=StrategySettings.model_fields["objectives"].description,
    ),
)
RunSettings = create_model("RunSettings", __base__=_RunSettings, **_GA_FIELDS)


class RunCreate(RunSettings):
    """`{"preset": "paper-voxel", "seed": 1, "shape": [5, 5, 3], ...}`."""

    seed: Seed = 0
    shape: ShapeIn | None = Field(
        None, description='bounding box [nx, ny, nz] in voxels (or "5x5x3", as the CLI takes it)'
    )


class SweepCreate(RunSettings):
    """One base config over many bounding boxes and seeds (default: the paper's nine, seeds 1-3),
    or over task presets and seeds (`tasks`: each task's own box unless `shapes` is given)."""

    shapes: list[ShapeIn] = Field(
        default_factory=lambda: list(PAPER_NINE_SHAPES),
        min_length=1,
        max_length=1000,
        description='bounding boxes, each [nx, ny, nz] (or "5x5x3")',
    )
    seeds: list[Seed] = Field(default_factory=lambda: [1, 2, 3], min_length=1, max_length=1000)
    # a Literal built from the task list at import time, which a checker cannot read
    tasks: list[Literal[tuple(TASKS)]] | None = Field(  # type: ignore[valid-type]
        None,
        min_length=1,
        max_length=len(TASKS),
        description="task presets to sweep instead of boxes (GET /presets), e.g. "
        '["task-flat", "task-slope"]',
    )


class RunProgress(BaseModel):
    generation: int = Field(description="generations committed")
    generations: int
    max_simulations: int | None = Field(
        None, description="the run's budget in simulations (its config's; null: generations alone)"
    )
    evaluations: int = Field(description="simulations run (committed generations)")
    saved: int = Field(description="individuals whose fitness came from the run's cache")
    fitness_saved: int = Field(description="individuals with a fitness in the database")
    evaluations_per_second: float | None
    best_fitness: float | None
    best_generation: int | None
    eta_seconds: float | None


class RunPublic(BaseModel):
    id: int
    status: RunStatus
    problem: str | None = Field(
        None, description="why an active run does not progress (the database cannot be written)"
    )
    preset: str | None
    seed: int
    sweep_id: int | None
    progress: RunProgress
    config: dict[str, Any]
    error: str | None
    created_at: datetime
    started_at: datetime | None
    finished_at: datetime | None
    takeovers: int = Field(description="times another coordinator took the run over")


class RunPage(BaseModel):
    items: list[RunPublic]
    total: int
    offset: int
    limit: int


class CurveRow(BaseModel):
    generation: int
    best: float | None
    mean: float | None
    median: float | None
    min: float | None
    best_so_far: float | None
    diversity: float
    evaluations: int
    saved: int
    failed: int
    std: float | None
    coverage: float | None = Field(
        None, description="runs with descriptors: filled fraction of the archive's cells"
    )
    qd_score: float | None = Field(None, description="and the sum of its elites' fitness")
    hypervolume: float | None = Field(
        None, description="with objectives: the hypervolume of the front so far (docs/evolution.md)"
    )
    front_size: int | None = Field(None, description="and its distinct points")
    normalised_hypervolume: float | None = Field(
        None,
        description="and its hypervolume with each objective scaled from its reference (0) to "
        "its ideal (1), so every objective weighs the same: 1 is a front holding the ideal "
        "point (docs/evolution.md; absent from generations committed before it existed)",
    )


class Curve(BaseModel):
    run_id: int
    generations: list[CurveRow]


class IndividualPublic(BaseModel):
    id: int = Field(description="generation * population + index")
    generation: int
    index: int
    fitness: float | None
    measures: dict[str, float | None] | None = Field(
        description='what the simulation measured, by name (docs/physics.md, "Measures and '
        'objectives"): speed, forward_speed, climb_rate, distance, heading, energy, '
        "cost_of_transport, efficiency, stable (1 or 0), ...; null for a value not measured "
        "(energy, unless the objective needs it), {} for a robot that could not be built, null "
        "while pending. Rows stored before revision 0004 hold the fitness's measure and heading"
    )
    status: IndividualStatus
    operator: str
    parents: list[int]
    genome_hash: str
    eval_seconds: float | None
    worker: str | None


class IndividualDetail(IndividualPublic):
    genome: dict[str, Any]
    robot: dict[str, Any] = Field(description="the robot file (softevo.robot/1)")


class IndividualPage(BaseModel):
    run_id: int
    items: list[IndividualPublic]
    total: int
    offset: int
    limit: int


class SweepBox(BaseModel):
    shape: Shape
    task: str | None = Field(None, description="the task preset, in a sweep over tasks")
    run_ids: list[int]
    statuses: list[str]
    completed: int
    best_mean: float | None
    best_std: float | None
    best_min: float | None
    best_max: float | None


class SweepPublic(BaseModel):
    id: int
    status: RunStatus
    created_at: datetime
    request: dict[str, Any]
    boxes: list[SweepBox]


class SweepPage(BaseModel):
    items: list[SweepPublic]
    total: int
    offset: int
    limit: int


class Preset(BaseModel):
    name: str
    description: str
    settings: dict[str, Any]


class AlgorithmSetting(BaseModel):
    """A shared run setting that a strategy reads."""

    name: str
    default: Any
    description: str


class AlgorithmPublic(BaseModel):
    """An installed search strategy (`softevo algorithms` prints the same)."""

    name: str = Field(description='the value of a run\'s "algorithm"')
    summary: str
    uses: list[AlgorithmSetting] = Field(description="the shared run settings it reads")
    options: dict[str, Any] = Field(
        description='JSON schema of its own settings, given as a run\'s "options"'
    )


class Health(BaseModel):
    """What is up. With SOFTEVO_API_TOKEN set, why a part is down (the exception) and the
    coordinator's identity and runs are shown only to a caller with the token."""

    status: Literal["ok", "degraded"]
    database: str
    redis: str
    workers: str | None = Field(None, description="with Redis: the queue's live workers")
    coordinator: dict[str, Any] | None


class Message(BaseModel):
    detail: str


class DescriptorAxis(BaseModel):
    name: str
    low: float
    high: float
    bins: int
    help: str


class ArchiveCell(BaseModel):
    cell: list[int] = Field(description="bin index along each descriptor")
    values: list[float] = Field(description="the elite's descriptor values")
    fitness: float
    generation: int
    index: int
    id: int = Field(description="generation * population + index, for /individuals/{id}")
    robot: dict[str, Any] | None = Field(None, description="its robot file, with ?robots=true")


class ArchivePublic(BaseModel):
    run_id: int
    generations: int = Field(description="committed generations the archive has seen")
    descriptors: list[DescriptorAxis]
    coverage: float
    qd_score: float
    cells: list[ArchiveCell]


class FrontPoint(BaseModel):
    generation: int
    index: int
    id: int = Field(description="generation * population + index, for /individuals/{id}")
    fitness: float | None
    operator: str
    measures: dict[str, float | None] = Field(description="its record of measures")
    robot: dict[str, Any] | None = Field(None, description="its robot file, with ?robots=true")


class FrontPublic(BaseModel):
    run_id: int
    generations: int = Field(description="committed generations the front has seen")
    objectives: list[dict[str, Any]] = Field(
        description="the run's objectives: measure, goal, hypervolume reference and ideal"
    )
    points: list[FrontPoint] = Field(
        description="the non-dominated set of every individual evaluated so far, each genome "
        "once (where it first appeared), in (generation, index) order"
    )
