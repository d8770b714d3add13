"""Replays served by the API: computed once per (robot, fps) and remembered, on the RQ workers
when the service has them (the API process then never loads the physics), else in two niced
processes of the API's own, which hand back JSON bytes (the API only splices them).

A replay is asked for on a plain GET, so it is bounded: at most `MAX_POSITIONS` mass positions
(`softevo.core.outputs.replay`), its fps rounded to a bucket, at most `RUNNING_AT_ONCE` simulated at
the same moment, one of them per client and pictures in one of them only (more are refused with
503, never queued on a request thread), and the last few kept within `CACHED_BYTES`, so a
dashboard refreshing, or many people watching one run, simulates a robot once.
"""

from __future__ import annotations

import json
import math
import threading
from collections import Counter, OrderedDict
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from typing import Any

from fastapi import Request, Response

from softevo.core.limits import MAX_REPLAY_POSITIONS
from softevo.core.robots.robot_file import robot_to_json

#: Most mass positions one replay carries (frames x masses).
MAX_POSITIONS = MAX_REPLAY_POSITIONS
#: Replays remembered (the newest), and the most bytes they may hold together (estimated).
CACHED = 8
CACHED_BYTES = 256 * 2**20
#: Replays simulated at the same moment; one more asked for is refused (503), not queued, so
#: no request thread waits on a simulation and `/healthz` and the curve stay fast.
RUNNING_AT_ONCE = 2
#: Replays and pictures one client (its address) may have made at once, and pictures at once in
#: all: a client looping on new parameters holds one slot at most, and the pictures leave a
#: slot to the replays (the dashboard's viewer). Requests past either are refused (503).
PER_CLIENT_AT_ONCE = 1
PICTURES_AT_ONCE = 1
#: Frame rates replays are recorded at: a request's fps is rounded to the nearest (in ratio), so
#: any fps does not force a new simulation.
FPS_BUCKETS = (0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 15.0, 20.0, 30.0, 60.0, 120.0)

#: (robot file, fps, max positions) -> replay; None: in this process (`use_workers` sets it)
Remote = Callable[[dict[str, Any], float, int], dict[str, Any]]
_remote: Remote | None = None
_cache: OrderedDict[tuple[str, float], bytes] = OrderedDict()
_lock = threading.Lock()
_computing: dict[tuple[str, float], threading.Lock] = {}
_slots = threading.BoundedSemaphore(RUNNING_AT_ONCE)
_held: Counter[str | None] = Counter()  # slots held by each client; None: by the pictures


class ReplayUnavailableError(RuntimeError):
    """The workers gave no replay (none live in time, the job failed): 503, saying why."""


class ReplayBusyError(RuntimeError):
    """RUNNING_AT_ONCE replays are being simulated: try again in a moment (503)."""


def use_workers(remote: Remote | None) -> None:
    """Compute replays with `remote` (the RQ workers) from now on; None: in this process."""
    global _remote
    _remote = remote


def fps_bucket(fps: float, buckets: tuple[float, ...] = FPS_BUCKETS) -> float:
    """The bucket nearest `fps` in ratio (14.999 and 15 share 15)."""
    return min(buckets, key=lambda bucket: abs(math.log(bucket / fps)))


@contextmanager
def slot(client: str | None, picture: bool = False) -> Iterator[None]:
    """One of the RUNNING_AT_ONCE slots for `client` (its address; None: unknown, not counted
    per client) for the time of the block, or ReplayBusyError (503) saying which bound is full:
    the client's own (PER_CLIENT_AT_ONCE), the pictures' (PICTURES_AT_ONCE) or all of them."""
    with _lock:
        if client is not None and _held[client] >= PER_CLIENT_AT_ONCE:
            raise ReplayBusyError(
                f"{PER_CLIENT_AT_ONCE} replay or picture you asked for is being made; ask for "
                "the next when it is done"
            )
        if picture and _held[None] >= PICTURES_AT_ONCE:
            raise ReplayBusyError(
                f"{PICTURES_AT_ONCE} picture is being drawn; try again in a few seconds"
            )
        if not _slots.acquire(blocking=False):
            raise ReplayBusyError(
                f"{RUNNING_AT_ONCE} replays are being simulated; try again in a few seconds"
            )
        holders = [who for who in (client,) if who is not None] + ([None] if picture else [])
        _held.update(holders)
    try:
        yield
    finally:
        with _lock:
            _held.subtract(holders)
            for who in holders:
                if _held[who] <= 0:
                    del _held[who]
        _slots.release()


def client_address(request: Request) -> str | None:
    """Who asks, for the per-client bound: the peer's address (behind a proxy, the address
    uvicorn's --proxy-headers gives), None when the server knows none."""
    return request.client.host if request.client else None


def replay(robot: Any, fps: float, client: str | None = None) -> bytes:
    """Frames at (up to) `fps` per simulated second, rounded to a bucket, as JSON bytes;
    simulated in one of `client`'s slots (`slot`) unless remembered."""
    key = _key(robot, fps)
    fps = key[1]
    with _lock:
        if key in _cache:
            _cache.move_to_end(key)
            return _cache[key]
        computing = _computing.setdefault(key, threading.Lock())
    with computing:  # one simulation per key, however many ask at once
        with _lock:
            if key in _cache:
                return _cache[key]
        try:
            with slot(client):
                data = _simulate(robot, fps)
        except BaseException:
            with _lock:
                _computing.pop(key, None)
            raise
        _remember(key, data)
    return data


def replay_response(robot: Any, fps: float, client: str | None, **head: Any) -> Response:
    """The replay as a JSON response, `head` (run id, fitness, ...) first: bytes spliced, never
    a million positions turned into objects in this process (that would stall its event loop)."""
    encoded = replay(robot, fps, client)
    prefix = json.dumps(head, separators=(",", ":"), allow_nan=False)[:-1].encode()
    body = encoded if not head else prefix + b"," + encoded[1:]
    return Response(content=body, media_type="application/json")


def _key(robot: Any, fps: float) -> tuple[str, float]:
    return json.dumps(robot_to_json(robot), sort_keys=True), fps_bucket(fps)


def _remember(key: tuple[str, float], data: bytes) -> None:
    """Cached before its lock goes, so a late caller finds it; the oldest go past the bounds."""
    with _lock:
        _cache[key] = data
        while len(_cache) > 1 and (
            len(_cache) > CACHED or sum(len(v) for v in _cache.values()) > CACHED_BYTES
        ):
            _cache.popitem(last=False)
        _computing.pop(key, None)


def _simulate(robot: Any, fps: float) -> bytes:
    if _remote is not None:
        try:
            data = _remote(robot_to_json(robot), fps, MAX_POSITIONS)
        except RuntimeError as error:
            raise ReplayUnavailableError(str(error)) from None
        return json.dumps(data, separators=(",", ":"), allow_nan=False).encode()
    from softevo.core.outputs.replay import replay_json

    try:  # in a process of its own: its CPU and its encoding leave this one free
        return _processes().submit(replay_json, robot_to_json(robot), fps, MAX_POSITIONS).result()
    except BrokenProcessPool:
        shutdown()
        raise ReplayUnavailableError("the replay's process died (out of memory?)") from None


_pool: ProcessPoolExecutor | None = None


def _processes() -> ProcessPoolExecutor:
    """The replays' own processes (RUNNING_AT_ONCE, niced, gone with this one), made on the
    first replay this process computes."""
    global _pool
    from softevo.core.physics.evaluation import pool_context, start_pool_process

    with _lock:
        if _pool is None:
            _pool = ProcessPoolExecutor(
                RUNNING_AT_ONCE,
                mp_context=pool_context(),
                initializer=start_pool_process,
            )
        return _pool


def shutdown() -> None:
    """Stop the replays' processes (the server stops, or one of them died)."""
    global _pool
    with _lock:
        pool, _pool = _pool, None
    if pool is not None:
        pool.shutdown(wait=False, cancel_futures=True)


def in_own_process(function: Callable[..., Any], *args: Any, client: str | None = None) -> Any:
    """`function(*args)` (a picture) in one of the replays' processes, in a picture's slot of
    `client`'s (`slot`): past a bound, ReplayBusyError, never queued on a request thread."""
    with slot(client, picture=True):
        try:
            return _processes().submit(function, *args).result()
        except BrokenProcessPool:
            shutdown()
            raise ReplayUnavailableError("the replay's process died (out of memory?)") from None
