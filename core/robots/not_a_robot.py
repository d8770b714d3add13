"""What a JSON document given as a robot file is, when it is another of softevo's files.

A run folder holds config.json, curve.json, state.json, cache.json and archive.json beside its
best_robot.json, and a run config looks like a robot file to a quick eye (both have shape, sim
and objective). Validated as a robot, such a file is refused field by field (twenty "extra
inputs" for a config.json); named for what it is, the mistake reads in one line.
"""

from __future__ import annotations

from collections.abc import Collection
from typing import Any

#: Fields of a run config (`softevo run`, POST /runs) that no robot file has.
RUN_CONFIG_FIELDS = frozenset(
    [
        "preset",
        "algorithm",
        "encoding",
        "population",
        "generations",
        "seed",
        "selection",
        "options",
        "objectives",
        "descriptors",
        "bins",
        "cube_options",
        "mutation_probability",
    ]
)

#: The other files of a `softevo run` folder, by the fields that only each of them has.
RUN_FILES: tuple[tuple[frozenset[str], str], ...] = (
    (frozenset({"run", "generations"}), "a run's learning curve (curve.json)"),
    (frozenset({"seed", "generation", "previous"}), "a run's search state (state.json)"),
    (frozenset({"generation", "elapsed", "fitness"}), "a run's fitness cache (cache.json)"),
    (frozenset({"descriptors", "bins", "elites"}), "a run's MAP-Elites archive (archive.json)"),
)

#: Other formats softevo writes, by their "format" field.
FORMATS = {"softevo.trajectory/1": "a trajectory (softevo simulate --trajectory)"}


def what_else(data: dict[str, Any], robot_fields: Collection[str]) -> str | None:
    """What `data` is if it is plainly not a robot file (None: validate it as one, so a robot
    file with a mistake is told its field)."""
    if "format" in data:
        return FORMATS.get(data["format"]) if isinstance(data["format"], str) else None
    keys = set(data)
    foreign = sorted(keys - set(robot_fields))
    if not foreign:
        return None  # a robot file without its "format": said as that field's error
    for fields, name in RUN_FILES:
        if fields <= keys:
            return name
    if keys & RUN_CONFIG_FIELDS:
        return "a run config"
    shown = ", ".join(foreign[:3]) + (", ..." if len(foreign) > 3 else "")
    return f"a JSON object with fields no robot file has ({shown})"
