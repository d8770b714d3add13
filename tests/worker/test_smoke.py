"""One real worker on a private Redis evaluates a batch exactly like the serial evaluator."""

from __future__ import annotations

import numpy as np
import pytest

from softevo.core.config import resolve
from softevo.core.evolution import Evolution
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.robots.robot_file import robot_to_json
from softevo.worker.evaluator import RQEvaluator

pytestmark = pytest.mark.redis


@pytest.mark.parametrize("worker_class", ["fork", "simple"])
def test_rq_evaluator_matches_the_serial_one(redis_server, workers, worker_class: str) -> None:
    """Both worker classes give the serial fitness and report the worker's own name."""
    workers.start("one", "--worker-class", worker_class)
    workers.wait_ready("one")
    evolution = Evolution.start(resolve({"preset": "quick", "population": 6, "seed": 2}))
    files = [robot_to_json(evolution.robot(item)) for item in evolution.individuals()]
    evaluator = RQEvaluator(redis_server.url)
    try:
        result = evaluator.evaluate_batch(files, key=f"smoke-{worker_class}")
    finally:
        evaluator.close()
    assert np.array_equal(
        result.fitness, SerialEvaluator().evaluate_batch(files).fitness, equal_nan=True
    )
    assert result.worker == "one" and result.seconds > 0


API_ON_RQ = """
import json, sys, time
from fastapi.testclient import TestClient
from softevo.api.app import create_app
from softevo.api.settings import Settings
database, redis = "sqlite:///" + sys.argv[1], sys.argv[2]
settings = Settings(database_url=database, redis_url=redis, poll_seconds=0.05)
with TestClient(create_app(settings)) as client:
    run = client.post("/runs", json={"preset": "quick", "population": 4, "generations": 2}).json()
    deadline = time.monotonic() + 60
    while client.get(f"/runs/{run['id']}").json()["status"] != "completed":
        assert time.monotonic() < deadline
        time.sleep(0.05)
    workers = {i["worker"] for i in client.get(f"/runs/{run['id']}/individuals").json()["items"]}
    best = client.get(f"/runs/{run['id']}/best").json()
    replay = client.get(f"/runs/{run['id']}/best/replay", params={"fps": 20}).json()
    again = client.get(f"/runs/{run['id']}/best/replay", params={"fps": 20}).json()  # remembered
print(json.dumps({"best": best, "replay": replay, "same": replay == again}))
print(sorted(w for w in workers if w), "numba" in sys.modules)
"""


def test_the_api_enqueues_without_loading_the_physics(redis_server, workers, tmp_path) -> None:
    """Runs and replays alike: the API on Redis has its robots simulated, and its replays
    recorded, by the workers, and never imports numba; the replay is the one this process
    computes for the same robot."""
    import json
    import subprocess
    import sys

    from softevo.core.outputs.replay import replay_frames
    from softevo.core.robots.robot_file import parse_robot

    workers.start("physics")
    workers.wait_ready("physics")
    done = subprocess.run(
        [sys.executable, "-c", API_ON_RQ, str(tmp_path / "api.db"), redis_server.url],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    *_, served, last = done.stdout.strip().splitlines()
    assert last == "['physics'] False"
    served = json.loads(served)
    local = replay_frames(parse_robot(served["best"]), 20.0)
    assert served["same"] and served["replay"]["frames"] == local["frames"]
    assert served["replay"]["speed"] == local["speed"] and served["replay"]["fps"] == local["fps"]


def test_the_first_job_pays_no_compilation(redis_server, workers, tmp_path, monkeypatch) -> None:
    """With an empty numba cache the kernels take seconds to compile; `softevo worker` does it
    before it takes jobs (and says how long it took), so its first job takes no longer than its
    second (each job's time is measured inside the job)."""
    import re

    evolution = Evolution.start(
        resolve({"preset": "quick", "population": 4, "seed": 3, "sim": {"duration": 1.0}})
    )
    files = [robot_to_json(evolution.robot(item)) for item in evolution.individuals()]
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba-cache"))  # empty: it compiles
    workers.start("warm")
    workers.wait_ready("warm", timeout=240)  # compiling, beside the rest of the suite
    warm = float(re.search(r"kernels warm \(([\d.]+) s\)", workers.log("warm")).group(1))
    evaluator = RQEvaluator(redis_server.url)
    try:
        first = evaluator.evaluate_batch(files, key="warm-first")
        second = evaluator.evaluate_batch(files, key="warm-second")
    finally:
        evaluator.close()
    print(
        f"\nworker on an empty numba cache: warm-up (compiling) {warm:.2f} s, then its first "
        f"job {first.seconds:.3f} s and its second {second.seconds:.3f} s"
    )
    assert np.array_equal(first.fitness, second.fitness, equal_nan=True)
    assert warm > 1.0, "nothing was compiled: the comparison says nothing"
    assert first.seconds < warm / 5
    assert first.seconds < 2 * second.seconds + 0.05


def api_on_redis(redis_url: str, tmp_path, **settings: float):  # type: ignore[no-untyped-def]
    """A started app on a SQLite file and this Redis (no worker unless the test starts one)."""
    from fastapi.testclient import TestClient

    from softevo.api.app import create_app
    from softevo.api.settings import Settings

    database = f"sqlite:///{tmp_path / 'api.db'}"
    return TestClient(
        create_app(
            Settings(database_url=database, redis_url=redis_url, poll_seconds=0.05, **settings)
        )  # type: ignore[arg-type]
    )


def test_a_replay_with_no_live_worker_is_a_503_not_a_hang(redis_server, tmp_path) -> None:
    """On Redis with no worker, a replay GET waits `replay_seconds`, then says why (503)."""
    import time

    with api_on_redis(redis_server.url, tmp_path, replay_seconds=1.0) as client:
        run = client.post("/runs", json={"preset": "quick", "population": 4}).json()["id"]
        deadline = time.monotonic() + 30
        while client.get(f"/runs/{run}/individuals").json()["total"] == 0:
            assert time.monotonic() < deadline
            time.sleep(0.05)
        started = time.monotonic()
        answer = client.get(f"/runs/{run}/individuals/0/replay")
        waited = time.monotonic() - started
        client.post(f"/runs/{run}/cancel")
    assert answer.status_code == 503 and "no result in 1 s" in answer.json()["detail"]
    assert waited < 10


def test_a_queue_without_a_live_worker_is_said(redis_server, workers, tmp_path) -> None:
    """On Redis with no worker, past SOFTEVO_NO_WORKER_SECONDS `/healthz` and the waiting run
    say so (with what to do), instead of a run that stays running in silence; a worker
    started then clears it."""
    import time

    with api_on_redis(redis_server.url, tmp_path, no_worker_seconds=1.0) as client:
        run = client.post("/runs", json={"preset": "quick", "population": 4, "generations": 2})
        run_id = run.json()["id"]
        deadline = time.monotonic() + 30
        while "no live worker" not in (client.get("/healthz").json()["workers"] or ""):
            assert time.monotonic() < deadline, client.get("/healthz").json()
            time.sleep(0.2)
        problem = client.get(f"/runs/{run_id}").json()["problem"]
        assert "no live worker" in problem and "softevo worker" in problem
        workers.start("late")
        while client.get(f"/runs/{run_id}").json()["status"] != "completed":
            assert time.monotonic() < deadline + 60
            time.sleep(0.1)
        while client.get("/healthz").json()["workers"] != "ok":  # workers are counted every 5 s
            assert time.monotonic() < deadline + 80
            time.sleep(0.2)


@pytest.mark.parametrize("descriptors", [["voxels", "soft"], ["heading", "soft"]])
def test_a_map_elites_run_on_two_rq_workers_builds_the_serial_archive(
    redis_server, workers, descriptors: list[str]
) -> None:
    """The archive and its curve columns do not depend on who simulated the robots, nor does
    the behavioural `heading` the workers measure."""
    for name in ("left", "right"):
        workers.start(name)
    for name in ("left", "right"):
        workers.wait_ready(name)
    request = {
        "preset": "quick",
        "population": 8,
        "generations": 3,
        "seed": 5,
        "shape": [2, 2, 2],
        "algorithm": "map-elites",
        "descriptors": descriptors,
        "bins": [4, 4],
        "sim": {"duration": 1.0},
    }
    serial = Evolution.start(resolve(request))
    serial.run(SerialEvaluator())
    on_rq = Evolution.start(resolve(request))
    evaluator = RQEvaluator(redis_server.url)
    try:
        on_rq.run(evaluator)
    finally:
        evaluator.close()
    assert on_rq.state.archive.to_json() == serial.state.archive.to_json()
    assert on_rq.curve() == serial.curve() and serial.curve()[-1]["coverage"] > 0


def test_nsga2_and_afpo_on_two_rq_workers_give_the_serial_curve_and_front(
    redis_server, workers
) -> None:
    """The front so far, the hypervolume and what each strategy breeds from (objective values,
    births, AFPO's lineages) do not depend on who simulated the robots, nor in what order."""
    for name in ("left", "right"):
        workers.start(name)
    for name in ("left", "right"):
        workers.wait_ready(name)
    evaluator = RQEvaluator(redis_server.url)
    try:
        for algorithm in ("nsga2", "afpo"):
            request = {
                "preset": "quick",
                "population": 6,
                "generations": 4,
                "seed": 5,
                "shape": [2, 2, 2],
                "algorithm": algorithm,
                "sim": {"duration": 1.0},
                "objectives": ["speed", "-cost_of_transport"],
                "max_simulations": 12,
                "options": {"variation": "explore"},
            }
            serial = Evolution.start(resolve(request))
            serial.run(SerialEvaluator())
            on_rq = Evolution.start(resolve(request))
            on_rq.run(evaluator)
            assert on_rq.curve() == serial.curve() and serial.curve()[-1]["hypervolume"] > 0
            assert on_rq.state.data == serial.state.data and serial.state.data["front"]
            counts = [row["evaluations"] for row in serial.curve()]
            assert sum(counts[:-1]) < 12 <= sum(counts) and len(counts) < 4  # the budget's end
    finally:
        evaluator.close()
