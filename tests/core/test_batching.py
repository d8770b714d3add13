"""Cross-run batching (`softevo.core.batching` and the local pool that uses it): tasks are whole
batches of one kind within the kernel's lanes, taken oldest first; and batches of many runs and
kinds, merged however they arrive, get exactly the fitness each robot gets alone."""

from __future__ import annotations

import copy
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from softevo.core.batching import Queue, Request, split_results
from softevo.core.config import resolve
from softevo.core.evaluation import PoolEvaluator, SerialEvaluator
from softevo.core.evolution import Evolution
from softevo.core.robot_file import robot_to_json


def robot_file(shape: list[int], duration: float = 3.0) -> dict[str, Any]:
    return {"format": "softevo.robot/1", "shape": shape, "sim": {"duration": duration}}


def test_a_task_is_the_oldest_batch_with_later_ones_of_its_kind_within_the_lanes() -> None:
    queue = Queue(lanes=8)
    a = Request([robot_file([3, 3, 3])] * 3, "runA-gen0-x")
    b = Request([robot_file([4, 4, 4])] * 2, "runB-gen0-x")
    c = Request([robot_file([3, 3, 3])] * 4, "runC-gen0-x")
    d = Request([robot_file([3, 3, 3])] * 2, "runD-gen0-x")  # would make 9 of 8: waits
    e = Request([robot_file([3, 3, 3], duration=5.0)] * 1, "runE-gen0-x")  # other settings
    for request in (a, b, c, d, e):
        queue.put(request)
    assert queue.take() == [a, c]
    assert queue.take() == [b]
    assert queue.take() == [d]
    assert queue.take() == [e]
    assert len(queue) == 0


def test_a_big_batch_or_one_retried_alone_is_a_task_by_itself() -> None:
    queue = Queue(lanes=4)
    big = Request([robot_file([3, 3, 3])] * 6, "big")
    small = Request([robot_file([3, 3, 3])] * 1, "small")
    retried = Request([robot_file([3, 3, 3])] * 1, "retried", alone=True)
    queue.put(big)
    queue.put(small)
    queue.put(retried, first=True)
    assert [queue.take() for _ in range(3)] == [[retried], [big], [small]]


def test_results_go_back_to_their_batches_and_a_prefix_leaves_the_queue() -> None:
    first, second = Request([{}, {}], "run1-gen0-a"), Request([{}], "run12-gen0-a")
    split_results([first, second], [0.1, None, 0.3])
    assert first.future.result() == [0.1, None] and second.future.result() == [0.3]
    queue = Queue()
    for request in (Request([{}], "run1-gen0-b"), Request([{}], "run12-gen0-b")):
        queue.put(request)
    assert [r.key for r in queue.remove("run1-")] == ["run1-gen0-b"]
    assert len(queue) == 1


def generation(seed: int, shape: list[int]) -> list[dict[str, Any]]:
    config = {"preset": "quick", "population": 6, "seed": seed, "shape": shape}
    evolution = Evolution.start(resolve(config))
    return [robot_to_json(evolution.robot(item)) for item in evolution.individuals()]


def test_batches_of_many_runs_merged_get_each_robots_own_fitness() -> None:
    """Twelve batches of one to three robots, of four runs and two kinds (shapes, and a longer
    duration), sent at once from twelve threads: the pool merges them into fewer kernel calls,
    and every robot's fitness equals, bit for bit, what it gets simulated alone."""
    runs = {seed: generation(seed, [3, 3, 3] if seed < 3 else [2, 2, 3]) for seed in (1, 2, 3, 4)}
    longer = copy.deepcopy(runs[4])
    for file in longer:
        file["sim"]["duration"] = 4.0
    batches = []
    for seed, files in [*runs.items(), (5, longer)]:
        batches += [(f"run{seed}-gen0-a", files[:1]), (f"run{seed}-gen0-b", files[1:3])]
    serial = SerialEvaluator()
    alone = [np.concatenate([serial.evaluate_batch([f]).fitness for f in files])
             for _, files in batches]  # fmt: skip
    with PoolEvaluator(2) as pool, ThreadPoolExecutor(len(batches)) as threads:
        futures = [threads.submit(pool.evaluate_batch, files, key) for key, files in batches]
        results = [future.result(timeout=120).fitness for future in futures]
        tasks = pool.tasks
    for expected, result in zip(alone, results, strict=True):
        assert np.array_equal(result, expected, equal_nan=True)
    assert tasks < len(batches), f"{tasks} kernel calls for {len(batches)} batches: none merged"
