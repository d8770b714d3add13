"""Replays and pictures share the replays' slots fairly: a movie's fps and duration are
quantised (14.999 and 15 fps share one movie), one client holds one slot at most, and the
pictures leave a slot to the replays, so one client's loop cannot make everyone else's replay
a 503."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from typing import Any

import pytest

from softevo.api import pictures, replay
from softevo.core.robots.robot import Actuation, VoxelRobot
from softevo.core.robots.settings import SimSettings

ROBOT = VoxelRobot((1, 1, 2), ("sine", "soft"), Actuation(0.1, 0.5, 0.0), SimSettings())


@pytest.fixture
def gate(monkeypatch: pytest.MonkeyPatch) -> Iterator[threading.Event]:
    """Replays and pictures that wait for the gate instead of simulating, caches emptied."""
    gate, started = threading.Event(), threading.Semaphore(0)
    monkeypatch.setattr(replay, "_cache", type(replay._cache)())
    monkeypatch.setattr(pictures, "_movies", type(pictures._movies)())

    def wait(*_args: Any) -> bytes:
        started.release()
        assert gate.wait(10)
        return b"{}"

    monkeypatch.setattr(replay, "_simulate", lambda _robot, _fps: wait())
    monkeypatch.setattr(replay, "_processes", lambda: _Inline(wait))
    gate.started = started  # type: ignore[attr-defined]
    yield gate
    gate.set()


class _Inline:
    def __init__(self, function: Any) -> None:
        self.function = function

    def submit(self, _function: Any, *args: Any) -> Any:
        result = self.function(*args)
        return type("Done", (), {"result": lambda _self: result})()


def held(gate: threading.Event, function: Any, *args: Any) -> threading.Thread:
    """`function(*args)` started in a thread and seen waiting at the gate."""
    thread = threading.Thread(target=function, args=args)
    thread.start()
    assert gate.started.acquire(timeout=10)  # type: ignore[attr-defined]
    return thread


def test_movies_quantise_fps_and_duration(monkeypatch: pytest.MonkeyPatch) -> None:
    drawn: list[tuple[float, float]] = []

    def draw(_function: Any, _file: Any, _format: str, fps: float, seconds: float, **_: Any):
        drawn.append((fps, seconds))
        return b"GIF"

    monkeypatch.setattr(pictures, "_movies", type(pictures._movies)())
    monkeypatch.setattr(pictures, "in_own_process", draw)
    for fps, seconds in ((15.0, 3.0), (14.999, 3.0001), (15.001, 2.9), (14.5, 3.2)):
        assert pictures.movie(ROBOT, "gif", fps, seconds) == b"GIF"
    assert drawn == [(15.0, 3.0)]
    assert pictures.quantise(0.6, 0.01) == (0.5, 0.5) and pictures.quantise(12, 6) == (12, 6)


def test_one_client_holds_one_slot(gate: threading.Event) -> None:
    first = held(gate, replay.replay, ROBOT, 30.0, "10.0.0.1")
    with pytest.raises(replay.ReplayBusyError, match="you asked for is being made"):
        replay.replay(ROBOT, 5.0, "10.0.0.1")
    second = held(gate, replay.replay, ROBOT, 5.0, "10.0.0.2")  # another client: the other slot
    gate.set()
    first.join(10), second.join(10)
    assert replay.replay(ROBOT, 1.0, "10.0.0.1") == b"{}"  # its slot is free again
    assert not replay._held


def test_pictures_leave_a_slot_to_replays(gate: threading.Event) -> None:
    """Two clients looping on pictures: the second is refused, a third's replay still runs."""
    drawing = held(gate, pictures.movie, ROBOT, "gif", 15.0, 3.0, "10.0.0.1")
    with pytest.raises(replay.ReplayBusyError, match="picture is being drawn"):
        pictures.movie(ROBOT, "gif", 12.0, 3.0, "10.0.0.2")
    viewing = held(gate, replay.replay, ROBOT, 30.0, "10.0.0.3")
    gate.set()
    drawing.join(10), viewing.join(10)
    assert not replay._held
