"""Run configurations and presets.

A run is asked for as a preset name plus any setting to override, e.g.
`{"preset": "paper-voxel", "seed": 1, "shape": [5, 5, 3], "sim": {"duration": 5}}`; `resolve`
merges the two (simulation settings key by key) and validates the result, naming the field of
any bad value, before anything runs.
"""

from __future__ import annotations

import math
from typing import Any

from pydantic import Field, ValidationError, field_validator, model_validator

from softevo.core.limits import MAX_SIDE, MAX_VOXELS
from softevo.core.objectives import Objective
from softevo.core.robots.encoding_registry import encoding_class, make_encoding
from softevo.core.robots.encodings import PAPER_CUBE_OPTIONS, Encoding, EncodingError
from softevo.core.robots.settings import SimSettings, format_validation_error
from softevo.core.robots.tasks import TASKS, task_presets
from softevo.core.search.configured import StrategySettings

CubeOption = tuple[float, float, float, float]
#: The paper's nine bounding boxes (Figure 4a), in its order.
PAPER_NINE_SHAPES: tuple[tuple[int, int, int], ...] = (
    (3, 3, 6),
    (4, 4, 3),
    (4, 4, 4),
    (5, 5, 3),
    (5, 5, 4),
    (5, 5, 5),
    (6, 6, 3),
    (6, 6, 6),
    (9, 9, 2),
)


class ConfigError(ValueError):
    """A run configuration that cannot run; the message names the field."""


def parse_shape(value: Any) -> tuple[int, int, int]:
    """A bounding box from [nx, ny, nz] or the CLI's "5x5x3"; a ValueError in the CLI's words."""
    if isinstance(value, str):  # "5x5x3", as the CLI takes it
        try:
            value = [int(part) for part in value.lower().split("x")]
        except ValueError:
            raise ValueError(f"expected NXxNYxNZ like 5x5x3, got {value!r}") from None
    if not isinstance(value, list | tuple) or len(value) != 3:
        raise ValueError(f"expected three sides [nx, ny, nz], got {value!r}")
    if not all(isinstance(v, int) and not isinstance(v, bool) for v in value):
        raise ValueError(f"sides must be integers, got {value!r}")
    if not all(1 <= v <= MAX_SIDE for v in value):
        raise ValueError(f"each side must be between 1 and {MAX_SIDE}, got {list(value)}")
    if math.prod(value) > MAX_VOXELS:
        raise ValueError(f"{math.prod(value)} voxels, more than the limit of {MAX_VOXELS}")
    return (value[0], value[1], value[2])


class RunConfig(StrategySettings):
    """Everything that defines a run: encoding, bounding box, seed, GA and simulation settings."""

    preset: str | None = None
    encoding: str = Field(
        "voxel",
        max_length=100,
        description="how genes become a robot, by name: one installed in the entry-point group "
        "`softevo.encodings` (built in: voxel, voxel-phase, cube-springs, spring, cppn)",
    )
    shape: tuple[int, int, int] = (4, 4, 4)
    seed: int = Field(0, ge=0, le=2**63 - 1)
    sim: SimSettings = Field(default_factory=SimSettings)
    objective: Objective = Field(
        "speed", description="the measure that is fitness (softevo.core.objectives)"
    )
    cube_options: tuple[CubeOption, ...] = PAPER_CUBE_OPTIONS
    max_simulations: int | None = Field(
        None,
        ge=1,
        le=10**9,
        description="a budget in simulations: the run ends at the first row (a generation, or "
        "a steady-state curve row) whose simulations so far reach it, or at `generations`, "
        "whichever comes first; null: generations alone",
    )

    @field_validator("shape", mode="before")
    @classmethod
    def _shape(cls, value: Any) -> tuple[int, int, int]:
        return parse_shape(value)

    @field_validator("cube_options", mode="before")
    @classmethod
    def _options(cls, value: Any) -> Any:
        if isinstance(value, list):
            return tuple(tuple(row) if isinstance(row, list) else row for row in value)
        return value

    @field_validator("encoding")
    @classmethod
    def _encoding(cls, value: str) -> str:
        try:
            encoding_class(value)
        except EncodingError as error:
            raise ValueError(str(error)) from None
        return value

    @model_validator(mode="after")
    def _consistent(self) -> RunConfig:
        if self.encoding == "cube-springs" and self.shape != (1, 1, 1):
            raise ValueError(
                "shape: the cube-springs encoding is one cube, shape must be 1x1x1, got "
                + "x".join(map(str, self.shape))
            )
        if self.encoding == "cube-springs" and len(self.cube_options) < 2:
            raise ValueError("cube_options: at least two options are needed to evolve")
        if self.descriptors and not encoding_class(self.encoding).describable:
            raise ValueError(
                f"descriptors: defined on voxel labels, so only for the voxel encodings and "
                f"cppn, not {self.encoding}"
            )
        omegas = {w for _, b, w, _ in self.cube_options if b != 0}
        if self.encoding == "cube-springs" and len(omegas) > 1:
            raise ValueError(f"cube_options: actuated options must share one w, got {omegas}")
        return self

    def make_encoding(self) -> Encoding:
        return make_encoding(self.encoding, self.shape, self.cube_options)

    def strategy_settings(self) -> StrategySettings:
        return StrategySettings.model_validate(
            {name: getattr(self, name) for name in StrategySettings.model_fields}
        )

    def to_json(self) -> dict[str, Any]:
        return self.model_dump(mode="json")


#: The paper's phase 3 as printed (section 4.3); 5 groups where the paper says "some groups".
_PAPER_VOXEL: dict[str, Any] = {
    "encoding": "voxel",
    "shape": [4, 4, 4],
    "population": 25,
    "generations": 100,
    "selection": "grouped",
    "groups": 5,
    "survival": 0.5,
    "crossover_probability": 1.0,
    "mutation_probability": 0.02,
    "mutation_genes": 2,
    "immigrants": 0.12,
}

#: Each preset is a partial RunConfig; unspecified fields take RunConfig's defaults.
PRESETS: dict[str, dict[str, Any]] = {
    "paper-cube": {
        "encoding": "cube-springs",
        "shape": [1, 1, 1],
        "population": 30,
        "generations": 1000,
        "selection": "grouped",
        "groups": 3,
        "survival": 0.2,
        "crossover_probability": 24 / 30,
        "mutation_probability": 0.2,
        "mutation_genes": 2,
        "immigrants": 0.0,
    },
    "paper-voxel": _PAPER_VOXEL,
    "voxel-plus": {**_PAPER_VOXEL, "mutation_probability": 0.5},
    "quick": {
        "encoding": "voxel",
        "shape": [3, 3, 3],
        "population": 16,
        "generations": 20,
        "selection": "grouped",
        "groups": 4,
        "survival": 0.5,
        "crossover_probability": 1.0,
        "mutation_probability": 0.5,
        "mutation_genes": 2,
        "immigrants": 0.125,
        "sim": {"profile": "physical", "duration": 3.0, "settle_time": 0.5},
    },
}

PRESETS.update(task_presets(_PAPER_VOXEL))
#: Quality-diversity on the paper's phase 3: the paper's operators on pairs of elites from the
#: archive, generation 0 and the immigrants drawn with label frequencies of their own (spread):
#: the configuration measured best (EXPERIMENTS.md). The preset before issue 38 (uniform random
#: genomes) is `"preset": "paper-voxel", "algorithm": "map-elites"`, to the last digit.
PRESETS["map-elites"] = {
    **_PAPER_VOXEL,
    "algorithm": "map-elites",
    "descriptors": ["voxels", "actuated"],
    "bins": [8, 8],
    "options": {"random": "spread"},
}

#: CPPN bodies in a big box: the paper's GA with NEAT variation (every copy mutated, half the
#: crossed children), 25 x 40 generations (docs/evolution.md).
PRESETS["cppn-8x8x8"] = {
    **_PAPER_VOXEL,
    "encoding": "cppn",
    "shape": [8, 8, 8],
    "generations": 40,
    "mutation_probability": 0.5,
}

PRESET_DESCRIPTIONS = {
    "paper-cube": "paper phase 2: one cube, 28 springs pick one of 4 [k,b,w,c] options",
    "paper-voxel": "paper phase 3: voxel robots in a bounding box (4x4x4 by default)",
    "voxel-plus": "paper-voxel with half the children mutated: it keeps improving where "
    "paper-voxel stalls (docs/evolution.md)",
    "quick": "a small voxel run for demos and tests (3x3x3, 16 x 20 generations, 3 s); it "
    "scores 2.5 s of motion at 1 rad/s, under half an actuation period, so its speeds are one "
    "lean, not a gait's (its seed-1 best: 1.354 m/s over 3 s, 1.005 over 5 s, in the physical "
    "profile)",
    "map-elites": "paper-voxel as MAP-Elites: the best robot of every cell of filled x actuated "
    "fraction (8 x 8), parents drawn from the archive, random genomes of spread label "
    "frequencies (docs/evolution.md)",
    "cppn-8x8x8": "a CPPN grows 8x8x8 crawlers (bodies, phases and amplitudes), the paper's "
    "GA with NEAT variation, 25 x 40 generations (docs/evolution.md)",
    **{name: f"paper-voxel task: {asks}" for name, (asks, _, _) in TASKS.items()},
}


def _default_map(merged: dict[str, Any], request: dict[str, Any]) -> None:
    """`map-elites` asked for without descriptors takes the `map-elites` preset's map (filled x
    actuated fraction); descriptors without bins take its 8 cells each. (An empty list given is
    refused as it was: only what was left out is filled in.)"""
    qd = PRESETS["map-elites"]
    if merged.get("algorithm") == "map-elites" and "descriptors" not in request:
        merged["descriptors"] = merged.get("descriptors") or qd["descriptors"]
    descriptors = merged.get("descriptors")
    given = isinstance(descriptors, list | tuple) and descriptors and "bins" not in request
    if given and descriptors and len(merged.get("bins") or ()) != len(descriptors):
        merged["bins"] = [qd["bins"][0]] * len(descriptors)


#: Options a new run of these strategies gets where its request leaves them out; a stored
#: config (which lists the options it ran with, or none) is read without them, so runs made
#: before keep their arithmetic. NSGA-II and AFPO explore (issue 51, docs/evolution.md).
NEW_RUN_OPTIONS: dict[str, dict[str, Any]] = {
    "nsga2": {"variation": "explore"},
    "afpo": {"variation": "explore"},
}


def _new_run_options(merged: dict[str, Any]) -> None:
    """Fill in `NEW_RUN_OPTIONS` for the options a new run's request leaves out."""
    defaults = NEW_RUN_OPTIONS.get(merged.get("algorithm", "ga"))
    options = merged.get("options", {})
    if defaults and isinstance(options, dict):
        merged["options"] = {**defaults, **options}


def resolve(request: dict[str, Any], new: bool = False) -> RunConfig:
    """Merge a preset with overrides and validate; ConfigError names the offending field.
    `new`: the request starts a run (`POST /runs`, `softevo run`, the library), which gets
    `NEW_RUN_OPTIONS`; a stored config is resolved without them.

    A `sim` that sets the legacy per-step `damping` and names no profile is read in the `paper`
    profile: so is every config stored before profiles existed (they list every setting)."""
    if not isinstance(request, dict):
        raise ConfigError(f"run config: expected an object, got {type(request).__name__}")
    preset = request.get("preset", "paper-voxel")
    if preset not in PRESETS:
        raise ConfigError(f"preset: unknown preset {preset!r} (known: {', '.join(PRESETS)})")
    misplaced = sorted(set(request) & set(SimSettings.model_fields))
    if misplaced:  # a simulation setting at the top: say where it goes
        name = misplaced[0]
        raise ConfigError(
            f"{name}: a simulation setting, so it goes inside sim: "
            f'{{"sim": {{"{name}": ...}}}} (sim.{name})'
        )
    merged = {**PRESETS[preset], **request, "preset": preset}
    other = merged.get("algorithm", "ga") != PRESETS[preset].get("algorithm", "ga")
    if other and "options" not in request:  # the preset's options are its algorithm's
        merged.pop("options", None)
    _default_map(merged, request)
    if new:
        _new_run_options(merged)
    sim_overrides = request.get("sim", {})
    if not isinstance(sim_overrides, dict):
        raise ConfigError("sim: expected an object of simulation settings")
    if "damping" in sim_overrides and "profile" not in sim_overrides:
        sim_overrides = {"profile": "paper", **sim_overrides}  # the legacy per-step damping
    merged["sim"] = {**PRESETS[preset].get("sim", {}), **sim_overrides}
    try:
        return RunConfig.model_validate(merged)
    except ValidationError as error:
        raise ConfigError(format_validation_error(error)) from None
