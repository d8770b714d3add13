"""One real worker on a private Redis evaluates a batch exactly like the serial evaluator."""

from __future__ import annotations

import numpy as np
import pytest

from core.config import resolve
from core.evaluation import SerialEvaluator
from core.evolution import Evolution
from core.robot_file import robot_to_json
from worker.evaluator import RQEvaluator

pytestmark = pytest.mark.redis


@pytest.mark.parametrize("worker_class", ["fork", "simple"])
def test_rq_evaluator_matches_the_serial_one(redis_server, workers, worker_class: str) -> None:
    """Both worker classes give the serial fitness and report the worker's own name."""
    workers.start("one", "--worker-class", worker_class)
    workers.wait_ready("one")
    evolution = Evolution.start(resolve({"preset": "quick", "population": 6, "seed": 2}))
    files = [robot_to_json(evolution.robot(item)) for item in evolution.algorithm.ask()]
    evaluator = RQEvaluator(redis_server.url)
    try:
        result = evaluator.evaluate_batch(files, key=f"smoke-{worker_class}")
    finally:
        evaluator.close()
    assert np.array_equal(result.fitness, SerialEvaluator().evaluate(files), equal_nan=True)
    assert result.worker == "one" and result.seconds > 0


API_ON_RQ = """
import sys, time
from fastapi.testclient import TestClient
from api.app import create_app
from api.settings import Settings
database, redis = "sqlite:///" + sys.argv[1], sys.argv[2]
settings = Settings(database_url=database, redis_url=redis, poll_seconds=0.05)
with TestClient(create_app(settings)) as client:
    run = client.post("/runs", json={"preset": "quick", "population": 4, "generations": 2}).json()
    deadline = time.monotonic() + 60
    while client.get(f"/runs/{run['id']}").json()["status"] != "completed":
        assert time.monotonic() < deadline
        time.sleep(0.05)
    workers = {i["worker"] for i in client.get(f"/runs/{run['id']}/individuals").json()["items"]}
print(sorted(w for w in workers if w), "numba" in sys.modules)
"""


def test_the_api_enqueues_without_loading_the_physics(redis_server, workers, tmp_path) -> None:
    import subprocess
    import sys

    workers.start("physics")
    workers.wait_ready("physics")
    done = subprocess.run(
        [sys.executable, "-c", API_ON_RQ, str(tmp_path / "api.db"), redis_server.url],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.strip().splitlines()[-1] == "['physics'] False"
