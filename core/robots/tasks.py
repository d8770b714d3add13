"""Task presets: a small benchmark suite on top of `paper-voxel` (4x4x4, 25 x 100, 10 s), in
the `physical` physics profile (damping in physical units, a step derived from the materials).

Each task is a terrain and the objective that fits it; everything else is the paper's phase 3,
so a task's runs differ from `paper-voxel` only in where the robot is and what it is scored by.
The robot starts on flat ground with its front face (the largest x of its masses at rest)
0.15 m before the first riser or bar, whatever its box (`softevo.core.robots.terrain.start_shift`):
a good paper-voxel crawler covers about half a metre in the 9 measured seconds, so it meets the
feature after a few seconds (with the first riser 0.5 m away, no robot of the first suite ever
reached it; with it at x = 4.15 m whatever the box, no 3x3x3 robot did: docs/tasks.md).
"""

from __future__ import annotations

from typing import Any

#: name -> (what it asks, terrain, objective)
TASKS: dict[str, tuple[str, dict[str, Any], str]] = {
    "task-flat": (
        "the paper's task: crawl as fast as possible on flat ground (speed, m/s)",
        {"kind": "flat"},
        "speed",
    ),
    "task-slope": (
        "climb a 10 degree slope rising along +x (climb: rise of the centre of mass, m/s)",
        {"kind": "slope", "angle_deg": 10.0},
        "climb",
    ),
    "task-stairs": (
        "climb stairs along +x: 0.2 m steps, 4.15 m treads (forward: progress along +x, m/s)",
        {"kind": "steps", "height": 0.2, "depth": 4.15},
        "forward",
    ),
    "task-rough": (
        "cross rough ground, a smooth random field of +-0.2 m (speed, m/s)",
        {"kind": "rough", "amplitude": 0.2, "wavelength": 3.0, "seed": 1},
        "speed",
    ),
    "task-hurdles": (
        "cross bars 0.15 m high and 0.5 m long every 4.15 m along +x (forward, m/s)",
        {"kind": "hurdles", "height": 0.15, "spacing": 4.15, "width": 0.5},
        "forward",
    ),
}


def task_presets(base: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The tasks as presets: `base` (paper-voxel) with the task's terrain and objective."""
    return {
        name: {
            **base,
            "sim": {**base.get("sim", {}), "profile": "physical", "terrain": terrain},
            "objective": objective,
        }
        for name, (_, terrain, objective) in TASKS.items()
    }
