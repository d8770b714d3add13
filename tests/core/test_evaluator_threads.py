"""The threads that wait on batches are shared and kept between generations, never more at once
than a call's window, and a forked child gets threads of its own."""

from __future__ import annotations

import os
import signal
import threading

import numpy as np

from softevo.core import evaluator
from softevo.core.evaluator import BatchResult, Evaluator, evaluate_in_batches


class Recording(Evaluator):
    """Remembers which thread evaluated each batch and how many ran at the same moment."""

    def __init__(self, capacity: int) -> None:
        self.workers, self.threads = capacity, []
        self.running = self.most = 0
        self.lock = threading.Lock()

    def evaluate_batch(self, robot_files, key=None):  # type: ignore[no-untyped-def]
        with self.lock:
            self.threads.append(threading.get_ident())
            self.running += 1
            self.most = max(self.most, self.running)
        threading.Event().wait(0.01)
        with self.lock:
            self.running -= 1
        return BatchResult(np.array([f["robot"] for f in robot_files], float), "rec", 0.0)

    def capacity(self) -> int:
        return self.workers

    def close(self) -> None:
        pass


def test_batch_threads_are_reused_by_the_next_call_and_the_window_holds() -> None:
    files = [{"robot": i} for i in range(40)]
    first = Recording(2)
    assert evaluate_in_batches(first, files, batch_size=4).tolist() == list(range(40))
    assert first.most <= 4  # two per worker out at once, the other six batches waited
    started = {thread.ident for thread in evaluator._HANDS._threads}  # by this and earlier calls
    assert set(first.threads) <= started
    second = Recording(2)
    evaluate_in_batches(second, files[:8], batch_size=4)
    assert set(second.threads) <= started  # no new thread for the next generation


def test_a_forked_child_evaluates_on_threads_of_its_own() -> None:
    evaluate_in_batches(Recording(2), [{"robot": 1}] * 4, batch_size=1)  # the parent's threads
    child = os.fork()
    if child == 0:
        values = evaluate_in_batches(Recording(2), [{"robot": 3}] * 4, batch_size=1)
        os._exit(0 if values.tolist() == [3.0] * 4 else 1)
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
