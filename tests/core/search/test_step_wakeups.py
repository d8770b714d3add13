"""When the step's thread wakes while batches run: when a batch lands once the hooks want it
(`check`'s due time), and at once when the hooks' alarm rings (a stop, which keeps what landed
and hands over no more batches). The batch threads are shared by every step of the process,
never more out at once than two per worker, and a forked child has threads of its own."""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pytest

from softevo.core import evaluator
from softevo.core.config import resolve
from softevo.core.evaluator import BatchResult, Evaluator
from softevo.core.evolution import Evolution
from softevo.core.search import stream
from softevo.core.search.step import Hooks


def _run(population: int, generations: int = 1) -> Evolution:
    """A random search of 3x3x3 robots (big enough that a batch holds `batch_size`, 4)."""
    request = {"preset": "quick", "algorithm": "random", "shape": [3, 3, 3], "seed": 1}
    return Evolution.start(
        resolve({**request, "population": population, "generations": generations})
    )


class Gated(Evaluator):
    """The first batch lands at once; every later one waits for `release`. Each robot's
    fitness is 1; `started` holds each batch's key, in the order they were handed over."""

    def __init__(self, capacity: int = 2, gate_first: bool = False) -> None:
        self.release, self.slots, self.gate_first = threading.Event(), capacity, gate_first
        self.started: list[str] = []
        self.lock = threading.Lock()
        self.threads: list[int] = []
        self.running = self.most = 0

    def evaluate_batch(self, robot_files: Sequence[dict[str, Any]], key: str | None = None):
        with self.lock:
            first = not self.started
            self.started.append(str(key))
            self.threads.append(threading.get_ident())
            self.running += 1
            self.most = max(self.most, self.running)
        if self.gate_first or not first:
            assert self.release.wait(30), "never released"
        with self.lock:
            self.running -= 1
        return BatchResult(np.ones(len(robot_files)), "gated", 0.0)

    def capacity(self) -> int:
        return self.slots

    def close(self) -> None:
        pass


class StoppedError(Exception):
    pass


class Listening(Hooks):
    """Hears of each batch (its indices); `check` returns `due` and raises once `stop` is set."""

    def __init__(self, due: Callable[[], float | None], on_batch: Callable[[], None]) -> None:
        self.alarm, self.stop = threading.Event(), threading.Event()
        self.due, self.on_batch = due, on_batch
        self.heard: list[list[int]] = []

    def check(self) -> float | None:
        if self.stop.is_set():
            raise StoppedError
        return self.due()

    def batch(self, generation: int, indices: list[int], result: BatchResult) -> None:
        self.heard.append(indices)
        self.on_batch()


def _in_thread(work: Callable[[], None]) -> tuple[threading.Thread, list[BaseException]]:
    raised: list[BaseException] = []

    def run() -> None:
        try:
            work()
        except BaseException as error:
            raised.append(error)

    thread = threading.Thread(target=run)
    thread.start()
    return thread, raised


@pytest.fixture
def slow_checks(monkeypatch: pytest.MonkeyPatch) -> None:
    """`check` would otherwise run only every hour: what happens sooner was woken for."""
    monkeypatch.setattr(stream, "CHECK_SECONDS", 3600.0)


def test_a_batch_landing_after_the_due_time_is_heard_of_before_the_rest(slow_checks: None) -> None:
    gated, evolution = Gated(), _run(population=2)
    released_when_heard: list[bool] = []

    def heard() -> None:
        released_when_heard.append(gated.release.is_set())
        gated.release.set()  # the second batch lands only after the first was heard of

    hooks = Listening(time.monotonic, heard)  # a write is due at once

    def step() -> None:
        evolution.stepper.step(evolution.state, evolution.cache, gated, hooks)

    thread, raised = _in_thread(step)
    thread.join(30)
    assert not thread.is_alive() and not raised
    assert sorted(hooks.heard) == [[0], [1]] and released_when_heard == [False, True]


def test_the_alarm_wakes_a_waiting_step_which_keeps_what_landed(
    slow_checks: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    gated, evolution = Gated(), _run(population=2)
    hooks = Listening(lambda: None, lambda: None)  # nothing is wanted before the row's end
    first_landed, evaluate = threading.Event(), stream.Flights._evaluate

    def evaluate_and_tell(self: stream.Flights, *args: Any) -> None:
        evaluate(self, *args)
        first_landed.set()

    monkeypatch.setattr(stream.Flights, "_evaluate", evaluate_and_tell)

    def step() -> None:
        evolution.stepper.step(evolution.state, evolution.cache, gated, hooks)

    thread, raised = _in_thread(step)
    assert first_landed.wait(30)
    hooks.stop.set()
    hooks.alarm.set()
    thread.join(30)
    gated.release.set()
    assert not thread.is_alive()  # stopped long before an hour's check
    assert len(raised) == 1 and isinstance(raised[0], StoppedError)
    assert len(hooks.heard) == 1  # the batch that landed reached the hooks; the other never did


def test_a_stopped_step_hands_over_no_more_batches() -> None:
    """Cancel stops the compute: once `check` raises, the batches not yet handed to the
    evaluator are dropped; at most two per worker were ever out."""
    gated, evolution = Gated(gate_first=True), _run(population=80)  # 20 batches of 4

    def due() -> None:  # a check that stops the step once four batches are out
        if len(gated.started) >= 4:
            raise StoppedError

    hooks = Listening(due, lambda: None)
    with pytest.raises(StoppedError):
        evolution.stepper.step(evolution.state, evolution.cache, gated, hooks)
    gated.release.set()
    time.sleep(0.05)
    assert len(gated.started) == 4  # two per worker out; the other 16 never handed over


def test_batch_threads_are_shared_by_the_next_step_and_the_window_holds() -> None:
    gated, evolution = Gated(), _run(population=40, generations=2)
    gated.release.set()
    evolution.step(gated)
    assert gated.most <= 4  # two per worker out at once, the other six batches waited
    started = {thread.ident for thread in evaluator._HANDS._threads}  # by this and earlier steps
    assert set(gated.threads) <= started
    evolution.step(gated)
    assert set(gated.threads) <= started  # no new thread for the next generation


def test_a_forked_child_steps_on_threads_of_its_own() -> None:
    parent = Gated()
    parent.release.set()
    _run(population=4).step(parent)  # the parent's threads
    child = os.fork()
    if child == 0:
        gated, evolution = Gated(), _run(population=4)
        gated.release.set()
        stats = evolution.step(gated)
        os._exit(0 if stats.best == 1.0 else 1)
    for _ in range(200):  # a child waiting on its parent's threads would hang: give it 10 s
        done, status = os.waitpid(child, os.WNOHANG)
        if done:
            break
        threading.Event().wait(0.05)
    else:
        os.kill(child, signal.SIGKILL)
        os.waitpid(child, 0)
        raise AssertionError("the forked child's batches never ran")
    assert os.waitstatus_to_exitcode(status) == 0
