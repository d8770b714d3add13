"""Small chunks of small robots run one robot at a time (`simulate_batch(small_alone=True)`, what
the job function asks for): the same bits as the batched kernel, and really another path."""

from __future__ import annotations

import numpy as np
import pytest

from softevo.core.config import resolve
from softevo.core.physics import kernels, simulate, simulate_batch
from softevo.core.physics.simulate import SMALL_WIDTH
from softevo.core.robots.settings import sim_settings

SIM = {"duration": 1.0, "settle_time": 0.3}


def cubes(count: int, seed: int = 1) -> list:
    """Paper-cube robots (8 lattice points) with random spring options."""
    config = resolve({"preset": "paper-cube", "seed": seed, "sim": SIM})
    encoding, rng = config.make_encoding(), np.random.default_rng(seed)
    return [encoding.to_robot(encoding.random(rng), config.sim) for _ in range(count)]


def voxel_robots(shape: list[int], count: int, seed: int = 2) -> list:
    config = resolve({"preset": "paper-voxel", "seed": seed, "shape": shape, "sim": SIM})
    encoding, rng = config.make_encoding(), np.random.default_rng(seed)
    return [encoding.to_robot(encoding.random(rng), config.sim) for _ in range(count)]


@pytest.fixture
def batched_calls(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """How many robots each call of the batched kernel carried."""
    calls: list[int] = []
    batched = kernels.simulate_many

    def counting(*args):  # type: ignore[no-untyped-def]
        calls.append(args[0].shape[1])
        return batched(*args)

    monkeypatch.setattr(kernels, "simulate_many", counting)
    return calls


@pytest.mark.parametrize("energy", [False, True])
def test_small_chunks_alone_give_the_batched_bits(energy: bool, batched_calls: list[int]) -> None:
    robots = cubes(3) + voxel_robots([2, 2, 2], 2) + voxel_robots([3, 3, 3], 2)
    alone = simulate_batch(robots, threads=2, energy=energy, small_alone=True)
    # the cubes and the 2x2x2 robots ran one at a time; the 3x3x3 ones (64 points) batched
    assert batched_calls == [1, 1]  # two threads: one 3x3x3 robot in each call
    batched_calls.clear()
    together = simulate_batch(robots, threads=2, energy=energy)
    assert sorted(batched_calls) == [1, 1, 1, 1, 1, 2]  # every group through the kernel
    for one, many, robot in zip(alone, together, robots, strict=True):
        assert one.final_positions.tobytes() == many.final_positions.tobytes()
        assert (one.com_start, one.com_end, one.speed) == (many.com_start, many.com_end, many.speed)
        assert one.heading == many.heading
        assert str(one.measures()) == str(many.measures())  # every measure, NaN where NaN
        assert np.array_equal(one.energy, many.energy, equal_nan=True)
        assert one.speed == simulate(robot, energy=energy)[0].speed


def test_chunks_of_enough_small_robots_still_share_the_kernel(batched_calls: list[int]) -> None:
    simulate_batch(cubes(SMALL_WIDTH), small_alone=True)
    assert batched_calls == [SMALL_WIDTH]


def test_a_cube_alone_measures_what_the_batch_does_on_a_slope() -> None:
    slope = sim_settings({**SIM, "terrain": {"kind": "slope", "angle_deg": 10.0}})
    robots = [robot.__class__(**{**robot.__dict__, "sim": slope}) for robot in cubes(2, seed=4)]
    alone = simulate_batch(robots, small_alone=True, energy=True)
    together = simulate_batch(robots, energy=True)
    for one, many in zip(alone, together, strict=True):
        assert one.final_positions.tobytes() == many.final_positions.tobytes()
        assert one.climb_rate == many.climb_rate
