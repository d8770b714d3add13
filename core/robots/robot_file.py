"""The robot file, `softevo.robot/1`: a stable JSON form of every robot softevo makes or reads.

    {"format": "softevo.robot/1",
     "shape": [nx, ny, nz],
     "voxels": [label, ...],                 # nx*ny*nz labels, x fastest, then y, then z
     "actuation": {"a": .., "b": .., "c": ..},   # genes of sine / neg_sine voxels: required
                                             # with any (0, 0, 0 would be a still robot)
     "sim": {"dt": .., ...},                 # overrides of the default SimSettings
     "objective": "speed",                   # optional: the measure that is its fitness
     "energy": true}                         # optional: measure the actuators' work (energy,
                                             # cost_of_transport) whatever the objective

A co-designed robot (the `voxel-phase` encoding) adds "phases" (rad, added to c) and, optionally,
"amplitudes" (in place of b): one number per voxel, null on every voxel that is not actuated.
Files without them load as they always did.

A robot whose springs carry their own [k, b, w, c] (the paper's phase 2 cube) lists them under
"springs" in the canonical spring order of `softevo.core.robots.lattice`, instead of material
labels. A robot of the `spring` encoding gives "spring_labels": one of soft, hard, sine, neg_sine
for every spring of the full grid lattice (all voxels filled), with "actuation" genes. For both,
"voxels", if given, only say which voxels are "filled" or "empty" (default: all filled).

Anything else is refused with a one-line message that names the field: unknown keys, wrong
lengths, unknown labels, wrong types, non-finite numbers, out-of-range genes or settings.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    StrictBool,
    ValidationError,
    field_validator,
)

from softevo.core.limits import MAX_FILE_BYTES, MAX_SIDE, MAX_VOXELS
from softevo.core.objectives import Objective
from softevo.core.robots.not_a_robot import what_else
from softevo.core.robots.robot import (
    ACTUATED_LABELS,
    GENE_BOUNDS,
    LABELS,
    Actuation,
    LabelledSpringRobot,
    Robot,
    RobotError,
    SpringRobot,
    VoxelRobot,
    build_mechanics,
)
from softevo.core.robots.settings import format_validation_error, sim_settings

FORMAT = "softevo.robot/1"

Side = Annotated[int, Field(strict=True, ge=1, le=MAX_SIDE)]
Number = Annotated[float, Field(strict=True, allow_inf_nan=False)]
SpringRow = Annotated[list[Number], Field(min_length=4, max_length=4)]


class RobotFileError(ValueError):
    """A robot file that cannot be read; the message is one line and names the field."""


def _gene(name: str) -> Any:
    low, high = GENE_BOUNDS[name]
    return Field(0.0, ge=low, le=high, allow_inf_nan=False)


class _ActuationModel(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)
    a: float = _gene("a")
    b: float = _gene("b")
    c: float = _gene("c")


class _SpringOption(BaseModel):
    """[k, b, w, c]: stiffness (N/m), relative amplitude, angular frequency (rad/s), phase (rad)."""

    k: Annotated[float, Field(ge=0, le=1e8, allow_inf_nan=False)]
    b: Annotated[float, Field(ge=-0.9, le=0.9, allow_inf_nan=False)]
    w: Annotated[float, Field(ge=0, le=1e4, allow_inf_nan=False)]
    c: Number


class _RobotModel(BaseModel):
    model_config = ConfigDict(extra="forbid")

    format: Literal["softevo.robot/1"]
    shape: Annotated[list[Side], Field(min_length=3, max_length=3)]
    voxels: list[str] | None = Field(None, max_length=MAX_VOXELS)
    springs: list[SpringRow] | None = Field(None, max_length=28 * MAX_VOXELS)
    spring_labels: list[str] | None = Field(None, max_length=28 * MAX_VOXELS)
    actuation: _ActuationModel | None = None
    sim: dict[str, Any] = Field(default_factory=dict)
    objective: Objective | None = None  # what the robot's fitness is (absent: speed)
    energy: StrictBool | None = None  # measure the actuators' work (absent: if the objective needs)
    phases: list[Number | None] | None = Field(None, max_length=MAX_VOXELS)
    amplitudes: list[Number | None] | None = Field(None, max_length=MAX_VOXELS)

    @field_validator("shape")
    @classmethod
    def _not_too_many(cls, shape: list[int]) -> list[int]:
        if math.prod(shape) > MAX_VOXELS:
            raise ValueError(f"{math.prod(shape)} voxels, more than the limit of {MAX_VOXELS}")
        return shape


def _refuse(field: str, message: str) -> RobotFileError:
    return RobotFileError(f"{field}: {message}")


def _check_labels(voxels: list[str], allowed: tuple[str, ...]) -> None:
    for index, label in enumerate(voxels):
        if label not in allowed:
            raise _refuse(
                f"voxels.{index}", f"unknown label {label!r} (expected one of {', '.join(allowed)})"
            )


def _occupancy(voxels: list[str] | None, n_voxels: int) -> tuple[bool, ...]:
    """Filled voxels of a robot whose springs carry their own materials (default: all)."""
    labels = voxels if voxels is not None else ["filled"] * n_voxels
    _check_labels(labels, ("empty", "filled"))
    return tuple(label == "filled" for label in labels)


def _per_voxel(
    values: list[float | None] | None, field: str, voxels: list[str], bounds: tuple[float, float]
) -> tuple[float, ...] | None:
    """A per-voxel list: a number on every actuated voxel, null on every other (stored as 0)."""
    if values is None:
        return None
    if len(values) != len(voxels):
        raise _refuse(field, f"expected {len(voxels)} values, one per voxel, got {len(values)}")
    for index, (value, label) in enumerate(zip(values, voxels, strict=True)):
        actuated = label in ACTUATED_LABELS
        if actuated and value is None:
            raise _refuse(f"{field}.{index}", f"a number is needed on a {label} voxel")
        if not actuated and value is not None:
            raise _refuse(f"{field}.{index}", f"must be null on a {label} voxel (not actuated)")
        if value is not None and not bounds[0] <= value <= bounds[1]:
            raise _refuse(f"{field}.{index}", f"{value} is outside [{bounds[0]}, {bounds[1]}]")
    return tuple(0.0 if value is None else float(value) for value in values)


def _actuated_needs_genes(model: _RobotModel) -> None:
    """sine / neg_sine labels without "actuation" are refused: the genes would silently be
    a = b = c = 0 and the robot would not move. Files softevo writes always carry them."""
    if model.actuation is not None or model.springs is not None:
        return
    field = "spring_labels" if model.spring_labels is not None else "voxels"
    labels = model.spring_labels if model.spring_labels is not None else model.voxels or []
    actuated = [label for label in labels if label in ("sine", "neg_sine")]
    if actuated:
        raise _refuse(
            "actuation",
            f"required: {field} has {len(actuated)} {actuated[0]} label(s); give "
            '{"a": .., "b": .., "c": ..} (the genes of the actuated springs)',
        )


def file_objective(data: dict[str, Any]) -> str:
    """The objective a (parsed, so valid) robot file's fitness is measured by."""
    return data.get("objective") or "speed"


def file_energy(data: dict[str, Any]) -> bool:
    """Whether a (parsed, so valid) robot file asks for the actuators' work to be measured."""
    return data.get("energy") is True


def parse_robot(data: Any) -> Robot:
    """Validate a decoded robot file and build the robot it describes."""
    _refuse_other(data)
    if "format" in data and data["format"] != FORMAT:
        raise _refuse("format", f"expected {FORMAT!r}, got {data['format']!r}")
    try:
        model = _RobotModel.model_validate(data)
    except ValidationError as error:
        raise RobotFileError(format_validation_error(error)) from None
    try:
        sim = sim_settings(model.sim)
    except ValidationError as error:
        raise RobotFileError(format_validation_error(error, prefix="sim")) from None
    n_voxels = math.prod(model.shape)
    if model.voxels is not None and len(model.voxels) != n_voxels:
        raise _refuse(
            "voxels",
            f"expected {n_voxels} labels for shape {list(model.shape)}, got {len(model.voxels)}",
        )
    if model.springs is not None and model.spring_labels is not None:
        raise _refuse("spring_labels", "give either 'springs' or 'spring_labels', not both")
    shape = (model.shape[0], model.shape[1], model.shape[2])
    _actuated_needs_genes(model)
    genes = model.actuation or _ActuationModel()
    actuation = Actuation(genes.a, genes.b, genes.c)
    robot: Robot
    per_spring = model.springs is not None or model.spring_labels is not None
    if per_spring and (model.phases is not None or model.amplitudes is not None):
        raise _refuse("phases", "per-voxel phases need voxel labels, not per-spring parameters")
    if model.spring_labels is not None:
        filled = _occupancy(model.voxels, n_voxels)
        robot = LabelledSpringRobot(shape, filled, tuple(model.spring_labels), actuation, sim)
    elif model.springs is not None:
        if model.actuation is not None:
            raise _refuse("actuation", "not allowed with 'springs' (each spring has its b, w, c)")
        filled = _occupancy(model.voxels, n_voxels)
        springs = np.array(model.springs, dtype=np.float64).reshape(-1, 4)
        for index, row in enumerate(springs):
            try:
                _SpringOption(k=row[0], b=row[1], w=row[2], c=row[3])
            except ValidationError as error:
                prefix = f"springs.{index}"
                raise RobotFileError(format_validation_error(error, prefix=prefix)) from None
        robot = SpringRobot(shape, filled, springs, sim)
    else:
        if model.voxels is None:
            raise _refuse("voxels", "required (or give per-spring parameters in 'springs')")
        _check_labels(model.voxels, LABELS)
        phases = _per_voxel(model.phases, "phases", model.voxels, (-math.inf, math.inf))
        amplitudes = _per_voxel(model.amplitudes, "amplitudes", model.voxels, GENE_BOUNDS["b"])
        if amplitudes is not None and phases is None:
            raise _refuse("amplitudes", "only with 'phases' (a co-designed robot)")
        robot = VoxelRobot(shape, tuple(model.voxels), actuation, sim, phases, amplitudes)
    try:  # what only the lattice knows: an empty grid, a spring count, a spring label
        build_mechanics(robot)
    except RobotError as error:
        raise RobotFileError(str(error)) from None
    return robot


#: The robot file a `softevo run` results folder holds: its best robot so far.
RESULTS_ROBOT = "best_robot.json"


def load_robot(path: str | Path) -> Robot:
    """Read and validate a robot file, or a `softevo run` results folder's best robot (its
    `best_robot.json`); every failure is a RobotFileError with a one-line reason (without the
    path, which the caller adds)."""
    path = Path(path)
    if path.is_dir():
        if not (path / RESULTS_ROBOT).is_file():
            raise RobotFileError(
                f"a folder without {RESULTS_ROBOT}: give a robot file, or a `softevo run` "
                "results folder"
            )
        path = path / RESULTS_ROBOT
    try:
        size = path.stat().st_size
    except OSError as error:
        raise RobotFileError(f"cannot read ({error.strerror})") from None
    if size > MAX_FILE_BYTES:
        raise RobotFileError(f"{size} bytes, more than the limit of {MAX_FILE_BYTES}")
    try:
        data = json.loads(path.read_text(encoding="utf-8"), parse_constant=_refuse_constant)
    except OSError as error:  # a special file, or one gone since stat
        raise RobotFileError(f"cannot read ({error.strerror})") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise RobotFileError(f"not valid JSON ({error})") from None
    except RecursionError:
        raise RobotFileError("JSON nested too deeply") from None
    except ValueError as error:
        raise RobotFileError(str(error)) from None
    _refuse_other(data, path)
    return parse_robot(data)


def _refuse_other(data: Any, path: Path | None = None) -> None:
    """Refuse what is not an object, or is another of softevo's files (named as what it is; for
    a file, with where its run's robot is), before validating it field by field."""
    if not isinstance(data, dict):
        raise RobotFileError(f"robot file: expected a JSON object, got {type(data).__name__}")
    other = what_else(data, _RobotModel.model_fields)
    if other is None:
        return
    said = f"{other}, not a robot file ({FORMAT})"
    if path is not None and (path.parent / RESULTS_ROBOT).is_file():
        said += f": the run's robot is {path.parent / RESULTS_ROBOT} (or give the folder)"
    elif path is not None:
        said += f": give a robot file, or a `softevo run` results folder (its {RESULTS_ROBOT})"
    raise RobotFileError(said)


def _refuse_constant(name: str) -> float:
    raise ValueError(f"non-finite number {name} is not allowed")


def robot_to_json(robot: Robot, sim: dict[str, Any] | None = None) -> dict[str, Any]:
    """The robot file of `robot`, with the full simulation settings it is simulated under: `sim`
    where the caller already holds `robot.sim.model_dump()` (a run's robot files share it, and
    nothing changes a robot file once made), else dumped here."""
    document: dict[str, Any] = {"format": FORMAT, "shape": list(robot.shape)}
    if isinstance(robot, VoxelRobot):
        document["voxels"] = list(robot.voxels)
        genes = robot.actuation
        document["actuation"] = {"a": genes.a, "b": genes.b, "c": genes.c}
        for key in ("phases", "amplitudes"):  # co-designed robots only: others stay as they were
            values = getattr(robot, key)
            if values is not None:
                document[key] = [
                    v if label in ACTUATED_LABELS else None
                    for v, label in zip(values, robot.voxels, strict=True)
                ]
    elif isinstance(robot, LabelledSpringRobot):
        document["voxels"] = ["filled" if f else "empty" for f in robot.filled]
        document["spring_labels"] = list(robot.spring_labels)
        genes = robot.actuation
        document["actuation"] = {"a": genes.a, "b": genes.b, "c": genes.c}
    else:
        document["voxels"] = ["filled" if f else "empty" for f in robot.filled]
        document["springs"] = np.asarray(robot.springs, dtype=np.float64).tolist()
    document["sim"] = robot.sim.model_dump() if sim is None else sim
    return document


def dump_robot(robot: Robot, path: str | Path) -> None:
    """Write `robot` as a robot file (pretty-printed, stable key order)."""
    Path(path).write_text(json.dumps(robot_to_json(robot), indent=1) + "\n", encoding="utf-8")


def with_sim(robot: Robot, **overrides: Any) -> Robot:
    """A copy of `robot` with some simulation settings changed; bad values raise RobotFileError."""
    try:
        return replace(robot, sim=sim_settings(overrides, base=robot.sim))
    except ValidationError as error:
        raise RobotFileError(format_validation_error(error, prefix="sim")) from None


__all__ = [
    "FORMAT",
    "RobotFileError",
    "dump_robot",
    "file_energy",
    "file_objective",
    "load_robot",
    "parse_robot",
    "robot_to_json",
    "with_sim",
]
