"""When a step's thread wakes while batches run: at the end, when a batch lands once the caller
wants it (`check`'s due time), and at once when the caller's alarm rings; and a stopped step
hands what landed to `on_batch` before it stops."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from softevo.core import evaluator
from softevo.core.evaluator import BatchResult, Evaluator, evaluate_in_batches


class Gated(Evaluator):
    """Batch `robot 0` lands at once; every other batch waits for `release`."""

    def __init__(self) -> None:
        self.release = threading.Event()

    def evaluate_batch(self, robot_files, key=None):  # type: ignore[no-untyped-def]
        if robot_files[0]["robot"] != 0:
            assert self.release.wait(30), "never released"
        return BatchResult(np.array([float(f["robot"]) for f in robot_files]), "gated", 0.0)

    def capacity(self) -> int:
        return 2

    def close(self) -> None:
        pass


class StoppedError(Exception):
    pass


@pytest.fixture
def slow_checks(monkeypatch: pytest.MonkeyPatch) -> None:
    """`check` would otherwise run only every hour: what happens sooner was woken for."""
    monkeypatch.setattr(evaluator, "CHECK_SECONDS", 3600.0)


def test_a_batch_landing_after_the_due_time_is_heard_of_before_the_rest(slow_checks: None) -> None:
    gated, heard = Gated(), []

    def on_batch(batch: list[int], result: BatchResult) -> None:
        heard.append(batch)
        gated.release.set()  # the second batch lands only after the first was heard of

    files = [{"robot": i} for i in range(2)]
    values = evaluate_in_batches(
        gated, files, batch_size=1, check=time.monotonic, on_batch=on_batch
    )
    assert values.tolist() == [0.0, 1.0]
    assert heard == [[0], [1]]


def test_the_alarm_wakes_a_waiting_step_which_keeps_what_landed(
    slow_checks: None, monkeypatch: pytest.MonkeyPatch
) -> None:
    gated, alarm, stop = Gated(), threading.Event(), threading.Event()
    heard: list[list[int]] = []
    first_landed, put = threading.Event(), evaluator._Landings.put

    def put_and_tell(self: evaluator._Landings, landing: evaluator.Landing) -> None:
        put(self, landing)
        first_landed.set()

    monkeypatch.setattr(evaluator._Landings, "put", put_and_tell)

    def check() -> None:  # None: nothing is wanted before the end
        if stop.is_set():
            raise StoppedError

    outcome: list[BaseException] = []

    def step() -> None:
        try:
            evaluate_in_batches(
                gated,
                [{"robot": i} for i in range(2)],
                batch_size=1,
                check=check,
                on_batch=lambda batch, _result: heard.append(batch),
                alarm=alarm,
            )
        except StoppedError as error:
            outcome.append(error)

    thread = threading.Thread(target=step)
    thread.start()
    assert first_landed.wait(30)
    stop.set()
    alarm.set()
    thread.join(30)
    gated.release.set()
    assert not thread.is_alive() and len(outcome) == 1  # stopped long before an hour's check
    assert heard == [[0]]  # the batch that landed reached the caller; the other never did
