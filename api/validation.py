"""From a request body to a `RunConfig`: merge with the preset, validate, check the ceilings.

Every refusal is a `RequestError` whose `loc` names the field, turned into a 422 with the same
shape as FastAPI's own validation errors, before anything is written or queued.
"""

from __future__ import annotations

import math
import re
from typing import Any

from softevo.api.cost import total_cost
from softevo.api.settings import Limits
from softevo.core.config import ConfigError, RunConfig, resolve
from softevo.core.robots.settings import SimSettings

_FIELD = re.compile(r"^([A-Za-z_][\w.]*): ")


class RequestError(ValueError):
    """A refused request body; `loc` is the path of the offending field."""

    def __init__(self, loc: list[str | int], message: str) -> None:
        super().__init__(message)
        self.loc = loc
        self.message = message

    def to_json(self) -> dict[str, Any]:
        return {"loc": ["body", *self.loc], "msg": self.message, "type": "value_error"}


def run_config(request: dict[str, Any], limits: Limits, prefix: tuple[str, ...] = ()) -> RunConfig:
    try:
        config = resolve(request)
    except ConfigError as error:
        message = str(error)
        match = _FIELD.match(message)
        loc: list[str | int] = [*prefix, *(match.group(1).split(".") if match else [])]
        raise RequestError(loc, message) from None
    check_limits(config, limits, prefix)
    check_budget([config], limits, [*prefix, "generations"])
    return config


def check_budget(configs: list[RunConfig], limits: Limits, loc: list[str | int]) -> None:
    """One run's, or a sweep's whole, cost against the service's budget (`api.cost`)."""
    cost = total_cost(configs)
    what = "this run" if len(configs) == 1 else f"these {len(configs)} runs"
    if cost.spring_steps > limits.max_spring_steps:
        raise RequestError(
            loc,
            f"{what} could simulate {cost.spring_steps:.3g} spring-steps "
            "(springs of the box x steps x simulations x the terrain's and "
            "objective's cost factor), over the budget of "
            f"{limits.max_spring_steps:.3g}; ask for less (population, "
            "generations, shape, sim.duration, sim.dt) or raise "
            "SOFTEVO_MAX_SPRING_STEPS",
        )
    if cost.stored_bytes > limits.max_stored_bytes:
        raise RequestError(
            loc,
            f"{what} would store about {cost.stored_bytes:.3g} bytes of "
            f"individuals, state and archive, over the budget of "
            f"{limits.max_stored_bytes:.3g}; ask for less (population, "
            "generations, shape, bins, options.window) or raise "
            "SOFTEVO_MAX_STORED_BYTES",
        )


def check_limits(config: RunConfig, limits: Limits, prefix: tuple[str, ...] = ()) -> None:
    """The service's ceilings, configurable with SOFTEVO_MAX_* variables."""

    def refuse(loc: list[str | int], message: str) -> None:
        raise RequestError([*prefix, *loc], message)

    if config.population > limits.max_population:
        refuse(
            ["population"],
            f"population: {config.population} is over the limit of "
            f"{limits.max_population} (SOFTEVO_MAX_POPULATION)",
        )
    if config.generations > limits.max_generations:
        refuse(
            ["generations"],
            f"generations: {config.generations} is over the limit of "
            f"{limits.max_generations} (SOFTEVO_MAX_GENERATIONS)",
        )
    voxels = math.prod(config.shape)
    if voxels > limits.max_voxels:
        refuse(
            ["shape"],
            f"shape: {voxels} voxels is over the limit of {limits.max_voxels} (SOFTEVO_MAX_VOXELS)",
        )
    if config.sim.duration > limits.max_duration:
        refuse(
            ["sim", "duration"],
            f"sim.duration: {config.sim.duration} s is over the limit "
            f"of {limits.max_duration} s (SOFTEVO_MAX_DURATION)",
        )
    if config.sim.step < limits.min_dt:
        refuse(
            ["sim", "dt"],
            f"sim.dt: {config.sim.step} s is under the limit of {limits.min_dt} s (SOFTEVO_MIN_DT)",
        )
    evaluations = config.population * config.generations
    if evaluations > limits.max_evaluations:
        refuse(
            ["generations"],
            f"population x generations = {evaluations} is over the limit "
            f"of {limits.max_evaluations} (SOFTEVO_MAX_EVALUATIONS)",
        )


def point_to_sim(problem: dict[str, Any]) -> dict[str, Any]:
    """A simulation setting sent at the top of a run or sweep body (`terrain`, `dt`) is refused
    as an extra input; say where it goes instead of only "Extra inputs are not permitted"."""
    loc = problem.get("loc", [])
    if problem.get("type") == "extra_forbidden" and len(loc) == 2 and loc[0] == "body":
        name = loc[1]
        if name in SimSettings.model_fields:
            message = (
                f'{name}: a simulation setting, so it goes inside sim: {{"sim": {{"{name}": ...}}}}'
            )
            return {**problem, "msg": message}
    return problem
