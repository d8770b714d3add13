"""The in-process evaluators (`softevo.core.physics.evaluation`): the pool survives a killed
process, and its processes come from a fork server that loaded the physics (spawned where none
can start)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from softevo.core.config import resolve
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import PRELOAD, PoolEvaluator, SerialEvaluator, pool_context
from softevo.core.robots.robot_file import robot_to_json
from tests.core.search.test_evolution import SMALL


def test_pool_rebuilds_itself_after_a_worker_process_is_killed() -> None:
    import os
    import signal

    evolution = Evolution.start(resolve({**SMALL, "seed": 3}))
    files = [robot_to_json(evolution.robot(item)) for item in evolution.individuals()]
    expected = SerialEvaluator().evaluate_batch(files).fitness
    with PoolEvaluator(2) as evaluator:
        assert np.array_equal(evaluator.evaluate_batch(files).fitness, expected, equal_nan=True)
        victim = next(iter(evaluator._pool._processes))  # a live pool process
        os.kill(victim, signal.SIGKILL)
        assert np.array_equal(evaluator.evaluate_batch(files).fitness, expected, equal_nan=True)
        assert victim not in evaluator._pool._processes


def test_pool_processes_come_from_the_fork_server_with_the_kernels_loaded() -> None:
    """A pool process is a child of the fork server (not of this process), which preloaded the
    physics, and gives the serial evaluator's fitness bit for bit."""
    import os

    evolution = Evolution.start(resolve({**SMALL, "seed": 4}))
    files = [robot_to_json(evolution.robot(item)) for item in evolution.individuals()]
    expected = SerialEvaluator().evaluate_batch(files).fitness
    assert pool_context().get_start_method() == "forkserver"
    with PoolEvaluator(2) as evaluator:
        assert np.array_equal(evaluator.evaluate_batch(files).fitness, expected, equal_nan=True)
        parents = {
            int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
            for pid in evaluator._pool._processes
        }
    assert os.getpid() not in parents and len(parents) == 1
    server = parents.pop()
    assert PRELOAD in Path(f"/proc/{server}/cmdline").read_text()


def test_pool_processes_are_spawned_where_the_fork_server_cannot_start(monkeypatch) -> None:
    from multiprocessing import forkserver

    def no_socket() -> None:
        raise OSError("no writable temporary folder")

    monkeypatch.setattr(forkserver, "ensure_running", no_socket)
    assert pool_context().get_start_method() == "spawn"
