"""The behavioural descriptor `heading`: what the simulation measures, that it is the same bits
however the robot was simulated, and MAP-Elites runs over it that give the same archive on any
number of processes and after a resume from disk."""

from __future__ import annotations

import json
import math

import pytest

from softevo.core.config import ConfigError, resolve
from softevo.core.nulls import to_null_record
from softevo.core.physics import simulate, simulate_batch
from softevo.core.physics.evaluation import PoolEvaluator, SerialEvaluator, evaluate_robot_files
from softevo.core.robots.robot import Actuation, VoxelRobot
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.robots.settings import sim_settings
from softevo.core.search.descriptors import CATALOGUE, MEASURED, describe
from softevo.core.search.evolution import Evolution
from softevo.results import read_resumable, write_results

HEADING = {
    "preset": "quick",
    "algorithm": "map-elites",
    "descriptors": ["heading", "voxels"],
    "bins": [8, 4],
    "population": 10,
    "generations": 4,
    "seed": 7,
    "sim": {"duration": 1.5},
}


def crawler() -> VoxelRobot:
    settings = sim_settings({"duration": 1.5, "settle_time": 0.25, "omega": 10.0})
    labels = ("sine", "hard", "neg_sine", "soft", "sine", "hard", "soft", "neg_sine")
    return VoxelRobot((2, 2, 2), labels, Actuation(0.1, 1.0, 0.3), settings)


def test_heading_is_the_direction_of_the_centre_of_mass_shift_in_the_trajectory() -> None:
    """By hand: the mean of the masses' positions in the frame at settle time and in the last
    frame, atan2 of the horizontal shift between them, in degrees."""
    robot = crawler()
    settle_step = robot.sim.settle_steps
    result, trajectory = simulate(robot, record_every=settle_step)
    assert trajectory is not None and trajectory.times[1] == pytest.approx(robot.sim.settle_time)
    start, end = trajectory.frames[1].mean(axis=0), trajectory.frames[-1].mean(axis=0)
    by_hand = math.degrees(math.atan2(end[1] - start[1], end[0] - start[0]))
    assert result.distance > 1e-3  # it moves, so the direction means something
    assert result.heading == pytest.approx(by_hand, abs=1e-6)
    assert -180.0 <= result.heading <= 180.0
    shift = [result.com_end[i] - result.com_start[i] for i in (0, 1)]
    assert result.heading == math.degrees(math.atan2(shift[1], shift[0]))  # the same bits


def test_heading_is_the_same_bits_alone_batched_and_through_the_job_function() -> None:
    robot = crawler()
    other = VoxelRobot((2, 2, 2), ("hard",) * 7 + ("sine",), Actuation(0.1, 1.0, 0.3), robot.sim)
    alone, _ = simulate(robot)
    batched = simulate_batch([other, robot, other, robot], lanes=3)
    assert [r.heading.hex() for r in batched[1::2]] == [alone.heading.hex()] * 2
    files = [robot_to_json(robot), {"format": "nonsense"}, robot_to_json(other)]
    measured = evaluate_robot_files(files)
    records = measured["measures"]
    assert records[1] is None  # a robot that could not be built has no record
    assert [records[0]["heading"], records[2]["heading"]] == [alone.heading, batched[0].heading]
    assert measured["fitness"][0] == alone.speed and measured["fitness"][1] is None


def test_a_robot_without_a_measured_heading_has_no_cell() -> None:
    labels, box = [1, 2, 3, 0, 0, 4], (3, 1, 2)
    assert describe(["heading", "voxels"], labels, box, {"heading": -90.0}) == (-90.0, 4 / 6)
    assert describe(["heading"], labels, box, {"heading": math.nan}) == ()
    assert describe(["heading"], labels, box) == ()
    assert {"heading"} == MEASURED
    assert (CATALOGUE["heading"].low, CATALOGUE["heading"].high) == (-180.0, 180.0)


def run(request: dict, evaluator) -> Evolution:
    evolution = Evolution.start(resolve(request))
    evolution.run(evaluator)
    return evolution


def test_the_same_seed_gives_the_same_heading_archive_on_one_and_two_processes() -> None:
    serial = run(HEADING, SerialEvaluator())
    with PoolEvaluator(1) as one, PoolEvaluator(2) as two:
        runs = [run(HEADING, one), run(HEADING, two)]
    for other in runs:
        assert other.state.archive.to_json() == serial.state.archive.to_json()
        assert other.curve() == serial.curve()
    elites = serial.state.archive.ordered()
    assert len({elite.cell[0] for elite in elites}) > 2  # the robots go several ways
    encoding = serial.algorithm.encoding
    for elite in elites[:3]:  # an elite's heading is its robot's, simulated again
        result, _ = simulate(encoding.to_robot(elite.genome, serial.config.sim))
        assert elite.values[0] == result.heading


def test_a_genome_met_again_keeps_its_heading_from_the_cache() -> None:
    """Elites bred again are taken from the cache (`saved`), their heading with them: the
    archive is the same as one whose cache knows nothing, where every one is simulated again."""
    whole = run(HEADING, SerialEvaluator())
    assert sum(row["saved"] for row in whole.curve()) > 0
    forgetful = Evolution.start(resolve(HEADING))
    with SerialEvaluator() as evaluator:
        while not forgetful.done:
            forgetful.step(evaluator)
            forgetful.cache.clear()
            forgetful.measures.clear()
    assert forgetful.state.archive.to_json() == whole.state.archive.to_json()


def test_a_run_resumed_from_its_folder_ends_with_the_same_heading_archive(tmp_path) -> None:
    whole = run(HEADING, SerialEvaluator())
    half = Evolution.start(resolve({**HEADING, "generations": 2}))
    with SerialEvaluator() as evaluator:
        half.run(evaluator)
        write_results(tmp_path, half)
        cache = json.loads((tmp_path / "cache.json").read_text())
        assert set(cache["measures"]) == set(cache["fitness"])
        resumed = read_resumable(tmp_path, HEADING["generations"])
        kept = {key: to_null_record(record) for key, record in resumed.measures.items()}
        assert kept == {key: to_null_record(record) for key, record in half.measures.items()}
        resumed.run(evaluator)
    assert resumed.state.archive.to_json() == whole.state.archive.to_json()
    assert resumed.curve() == whole.curve()


def test_a_bad_descriptor_name_lists_the_catalogue_with_heading() -> None:
    with pytest.raises(ConfigError, match="known: voxels, actuated, soft, height, heading"):
        resolve({**HEADING, "descriptors": ["heading", "drift"]})
