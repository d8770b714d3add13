"""Robots re-set in another physics profile, for the benches that compare profiles."""

from __future__ import annotations

import dataclasses

from softevo.core.robots.robot import Robot
from softevo.core.robots.settings import PROFILES, sim_settings


def in_profile(robot: Robot, profile: str, **settings: object) -> Robot:
    """`robot` with the settings its profile governs (dt and the damping) taken from `profile`
    instead of its file, and `settings` on top; everything else (materials, times) kept."""
    sim = robot.sim.model_dump()
    for name in PROFILES["paper"]:
        sim.pop(name, None)
    return dataclasses.replace(robot, sim=sim_settings({**sim, "profile": profile, **settings}))
