"""The evaluator contract, one suite run against every backend: the in-process serial evaluator,
the local process pool, and RQ workers on a private Redis (two real `softevo worker` processes).

What the generation step relies on (`softevo.core.evaluator.Evaluator`, whose whole interface is
`evaluate_batch`, `capacity`, `close`, a context manager and an optional `drop` for a cancelled
run's batches): the same robot files give the same
fitness, bit for bit, in the same order, whichever backend, process or batch simulated them; an
empty batch is an empty array; a robot file that cannot be built is NaN (failed, never 0) for
that robot alone; a batch's key changes nothing in its result; and batches evaluated from many
threads at once give the same results.
"""

from __future__ import annotations

import copy
import math
import time
import uuid
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
import pytest

from softevo.core.config import resolve
from softevo.core.evaluator import BatchDroppedError, Evaluator
from softevo.core.physics.evaluation import PoolEvaluator, SerialEvaluator
from softevo.core.robots.robot_file import robot_to_json
from softevo.core.search.evolution import Evolution
from softevo.worker.evaluator import RQEvaluator
from tests.services import RedisServer, Workers

SEEDS = (1, 2, 3)


def robot_files(seed: int) -> list[dict[str, Any]]:
    """The first generation of a quick run: eight robot files (`softevo.robot/1`)."""
    evolution = Evolution.start(resolve({"preset": "quick", "population": 8, "seed": seed}))
    return [robot_to_json(evolution.robot(item)) for item in evolution.individuals()]


@pytest.fixture(scope="module")
def files() -> dict[int, list[dict[str, Any]]]:
    return {seed: robot_files(seed) for seed in SEEDS}


@pytest.fixture(scope="module")
def reference(files: dict[int, list[dict[str, Any]]]) -> dict[int, np.ndarray]:
    """What the serial evaluator says, robot by robot: the truth every backend must match."""
    serial = SerialEvaluator()
    return {seed: serial.evaluate_batch(batch).fitness for seed, batch in files.items()}


def unbuildable(good: dict[str, Any]) -> list[Any]:
    """Robot files no backend can build: an unknown label, missing keys, not an object."""
    unknown_label = copy.deepcopy(good)
    unknown_label["voxels"][0] = "rubber"
    return [unknown_label, {"format": "softevo.robot/1", "shape": [3, 3, 3]}, "not a robot"]


@pytest.fixture(
    scope="module",
    params=["serial", "pool", pytest.param("rq", marks=pytest.mark.redis)],
)
def evaluator(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[Evaluator]:
    """Each backend once per module (starting a pool or two workers is the slow part)."""
    if request.param == "serial":
        yield SerialEvaluator()
        return
    if request.param == "pool":
        with PoolEvaluator(2) as pool:
            yield pool
        return
    workdir = tmp_path_factory.mktemp("rq")
    server = RedisServer(workdir)
    server.start()
    workers = Workers(server.url, workdir)
    try:
        for name in ("contract-a", "contract-b"):
            workers.start(name)
        for name in ("contract-a", "contract-b"):
            workers.wait_ready(name)
        rq = RQEvaluator(server.url, poll_seconds=0.2)
        try:
            yield rq
        finally:
            rq.close()
    finally:
        workers.stop_all()
        server.kill()


def key() -> str:
    """A fresh batch key, so no backend can hand back a result of another test."""
    return f"contract-{uuid.uuid4().hex[:12]}"


def test_same_fitness_as_serial_bit_for_bit_in_order(
    evaluator: Evaluator,
    files: dict[int, list[dict[str, Any]]],
    reference: dict[int, np.ndarray],
) -> None:
    for seed in SEEDS:
        result = evaluator.evaluate_batch(files[seed], key())
        assert isinstance(result.fitness, np.ndarray)
        assert result.fitness.dtype == np.float64
        assert result.fitness.shape == (len(files[seed]),)
        assert np.array_equal(result.fitness, reference[seed], equal_nan=True), seed
        assert result.worker, "a batch names who evaluated it"
        assert result.seconds > 0
    # Order is preserved: the same robots reversed, and mixed across seeds, come back in step.
    backwards = evaluator.evaluate_batch(files[1][::-1], key())
    assert np.array_equal(backwards.fitness, reference[1][::-1], equal_nan=True)
    mixed = [files[seed][i] for i in range(8) for seed in SEEDS]
    expected = np.array([reference[seed][i] for i in range(8) for seed in SEEDS])
    assert np.array_equal(evaluator.evaluate_batch(mixed, key()).fitness, expected, equal_nan=True)
    # One robot alone, and the same robot twice in a batch: still the same number.
    alone = evaluator.evaluate_batch(files[2][3:4], key()).fitness
    assert np.array_equal(alone, reference[2][3:4], equal_nan=True)
    twice = evaluator.evaluate_batch([files[2][3], files[2][3]], key()).fitness
    assert np.array_equal(twice, np.repeat(reference[2][3], 2), equal_nan=True)


def test_an_empty_batch_is_an_empty_array(evaluator: Evaluator) -> None:
    result = evaluator.evaluate_batch([], key())
    assert isinstance(result.fitness, np.ndarray)
    assert result.fitness.shape == (0,)
    assert evaluator.evaluate_batch([]).fitness.shape == (0,)


def test_a_robot_that_cannot_be_built_is_nan_alone(
    evaluator: Evaluator,
    files: dict[int, list[dict[str, Any]]],
    reference: dict[int, np.ndarray],
) -> None:
    good = files[3]
    bad = unbuildable(good[0])
    batch = [bad[0], good[0], good[1], bad[1], good[2], bad[2], good[3]]
    broken = [0, 3, 5]
    result = evaluator.evaluate_batch(batch, key())
    assert result.fitness.shape == (len(batch),)
    for index in broken:
        assert math.isnan(result.fitness[index]), f"robot {index} cannot be built: NaN, never 0"
    kept = [i for i in range(len(batch)) if i not in broken]
    assert np.array_equal(result.fitness[kept], reference[3][:4], equal_nan=True)
    assert result.worker and result.seconds > 0
    # A batch of nothing but unbuildable robots: all NaN, nothing raised.
    assert np.isnan(evaluator.evaluate_batch(bad, key()).fitness).all()


def test_a_robot_whose_settings_overflow_is_nan_alone(
    evaluator: Evaluator,
    files: dict[int, list[dict[str, Any]]],
    reference: dict[int, np.ndarray],
) -> None:
    """dt = 1e-310 passes `dt > 0`, but duration / dt overflows to inf: the settings refuse it
    like any other bad value, so that robot fails alone, on every backend."""
    good = files[1]
    overflow = copy.deepcopy(good[0])
    overflow["sim"]["dt"] = 1e-310
    result = evaluator.evaluate_batch([good[0], overflow, good[1]], key())
    assert math.isnan(result.fitness[1])
    assert np.array_equal(result.fitness[[0, 2]], reference[1][:2], equal_nan=True)


def test_the_key_names_a_batch_and_changes_no_result(
    evaluator: Evaluator,
    files: dict[int, list[dict[str, Any]]],
    reference: dict[int, np.ndarray],
) -> None:
    batch = files[2][:5] + unbuildable(files[2][0])[:1]
    plain = evaluator.evaluate_batch(batch).fitness
    assert isinstance(plain, np.ndarray)
    assert np.array_equal(plain, evaluator.evaluate_batch(batch, key()).fitness, equal_nan=True)
    assert np.array_equal(plain[:5], reference[2][:5], equal_nan=True)
    assert math.isnan(plain[5])


def test_concurrent_batches_from_threads_give_the_same_results(
    evaluator: Evaluator,
    files: dict[int, list[dict[str, Any]]],
    reference: dict[int, np.ndarray],
) -> None:
    """Twice `capacity()` threads, each with batches of its own (some sharing robots, one empty, one
    with an unbuildable robot), all at once: every batch gets its own robots' fitness back."""
    batches: list[tuple[list[Any], np.ndarray]] = []
    for seed in SEEDS:
        for start, stop in ((0, 3), (3, 8), (0, 8), (5, 6)):
            batches.append((files[seed][start:stop], reference[seed][start:stop]))
    bad = unbuildable(files[1][0])[0]
    with_bad = np.array([reference[1][0], np.nan, reference[1][1]])
    batches.append(([files[1][0], bad, files[1][1]], with_bad))
    batches.append(([], np.empty(0)))
    with ThreadPoolExecutor(max_workers=2 * evaluator.capacity()) as pool:
        futures = [pool.submit(evaluator.evaluate_batch, batch, key()) for batch, _ in batches]
        results = [future.result(timeout=120) for future in futures]
    for (batch, expected), result in zip(batches, results, strict=True):
        assert np.array_equal(result.fitness, expected, equal_nan=True)
        if batch:
            assert result.worker and result.seconds > 0


def test_capacity_counts_what_runs_at_once(evaluator: Evaluator) -> None:
    """Serial: 1; the pool: its 2 processes; RQ: the 2 workers registered on the queue."""
    expected = 1 if isinstance(evaluator, SerialEvaluator) else 2
    assert evaluator.capacity() == expected


def test_every_backend_is_the_one_narrow_interface(evaluator: Evaluator) -> None:
    assert isinstance(evaluator, Evaluator)
    assert Evaluator.__abstractmethods__ == {"evaluate_batch", "capacity", "close"}
    for name in ("evaluate", "workers", "concurrency"):  # the old second ways, gone
        assert not hasattr(evaluator, name), name


def lengthened(files: list[dict[str, Any]], duration: float) -> list[dict[str, Any]]:
    longer = copy.deepcopy(files)
    for file in longer:
        file["sim"]["duration"] = duration
    return longer


@pytest.mark.fault
def test_dropped_batches_stop_within_seconds_and_the_others_go_on(
    evaluator: Evaluator, files: dict[int, list[dict[str, Any]]]
) -> None:
    """A cancelled run's batches (`drop("runX-")`), one running and one waiting, each of about
    half a minute: the pool and RQ give both up within seconds, and another run's batch in
    flight at the same moment still gets its own fitness, bit for bit. In process (serial),
    `drop` gives up nothing: a batch of the dropped prefix is evaluated as usual."""
    if isinstance(evaluator, SerialEvaluator):
        evaluator.drop("serial-dropped-")
        result = evaluator.evaluate_batch(files[1][:2], "serial-dropped-gen0")
        assert np.isfinite(result.fitness).all()
        return
    run = uuid.uuid4().hex[:8]
    long = lengthened(files[1][:2], 1200.0)  # many seconds a robot on this machine
    other = lengthened(files[2][:1], 300.0)
    expected = SerialEvaluator().evaluate_batch(other).fitness
    with ThreadPoolExecutor(max_workers=3) as threads:
        first = threads.submit(evaluator.evaluate_batch, long[:1], f"runX{run}-gen0-a")
        others = threads.submit(evaluator.evaluate_batch, other, f"runY{run}-gen0-a")
        second = threads.submit(evaluator.evaluate_batch, long[1:], f"runX{run}-gen0-b")
        time.sleep(1.5)  # every batch handed over: two running, one waiting
        dropped_at = time.monotonic()
        evaluator.drop(f"runX{run}-")
        for future in (first, second):
            with pytest.raises(BatchDroppedError, match=f"runX{run}"):
                future.result(timeout=20)
        took = time.monotonic() - dropped_at
        result = others.result(timeout=120)
    print(f"[drop] {type(evaluator).__name__}: both dropped batches gave up {took:.2f} s after")
    assert took < 10
    assert np.array_equal(result.fitness, expected, equal_nan=True)
    if isinstance(evaluator, RQEvaluator):  # nothing of the dropped run left queued or running
        deadline = time.monotonic() + 10
        while True:
            left = [
                job
                for job in (
                    *evaluator.queue.job_ids,
                    *evaluator.queue.started_job_registry.get_job_ids(),
                )
                if f"runX{run}" in job
            ]
            if not left or time.monotonic() > deadline:
                break
            time.sleep(0.2)
        assert left == []
