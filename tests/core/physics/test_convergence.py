"""Results that do not depend on the time step (issue 49): a small version of
`bench/convergence.py`. In the physical profile every speed of a fixed set (the examples and
three champions) at the derived dt is within 2 % (or 1 mm/s) of its value at dt/4, and the set
ranks the same; in the paper profile, whose damping is per step, the crawler's is not."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from softevo.core.physics import simulate_batch
from softevo.core.robots.robot import Robot
from softevo.core.robots.robot_file import load_robot
from softevo.core.robots.settings import PROFILES, sim_settings

ROOT = Path(__file__).resolve().parents[3]
FILES = [
    *(ROOT / "examples" / f"{name}.json" for name in ("crawler_4x4x4", "paper_cube")),
    *(ROOT / "docs" / "experiments" / f"best_{box}.json" for box in ("4x4x3", "4x4x4", "9x9x2")),
]
#: Shorter than the files' 10 s, to keep the test quick (the bench runs them whole).
TIMES = {"duration": 4.0, "settle_time": 1.0}


def in_profile(robot: Robot, profile: str, divide: float = 1.0) -> Robot:
    sim = {k: v for k, v in robot.sim.model_dump().items() if k not in PROFILES["paper"]}
    settings = sim_settings({**sim, **TIMES, "profile": profile})
    divided = sim_settings({**settings.model_dump(), "dt": settings.step / divide})
    return dataclasses.replace(robot, sim=divided)


def speeds(profile: str, divide: float) -> list[float]:
    robots = [in_profile(load_robot(path), profile, divide) for path in FILES]
    return [result.speed for result in simulate_batch(robots)]


@pytest.fixture(scope="module")
def physical() -> tuple[list[float], list[float]]:
    return speeds("physical", 1.0), speeds("physical", 4.0)


def test_every_speed_is_within_two_percent_of_its_value_at_a_quarter_of_the_step(
    physical: tuple[list[float], list[float]],
) -> None:
    coarse, fine = physical
    assert max(fine) > 0.05  # the set really moves
    for path, at_dt, at_quarter in zip(FILES, coarse, fine, strict=True):
        assert abs(at_dt - at_quarter) <= max(0.02 * abs(at_quarter), 1e-3), path.name


def test_the_set_ranks_the_same_at_dt_and_at_a_quarter_of_it(
    physical: tuple[list[float], list[float]],
) -> None:
    coarse, fine = physical
    order = sorted(range(len(FILES)), key=fine.__getitem__)
    assert sorted(range(len(FILES)), key=coarse.__getitem__) == order


def test_the_paper_profiles_per_step_damping_does_not_converge() -> None:
    crawler = load_robot(FILES[0])
    at_dt, at_quarter = (
        simulate_batch([in_profile(crawler, "paper", divide)])[0].speed for divide in (1.0, 4.0)
    )
    assert abs(at_dt - at_quarter) > 0.2 * abs(at_quarter)  # measured: 41 % at 10 s
