"""Property-based tests of the whole REST API against its own OpenAPI schema (schemathesis).

Every operation is called with generated requests, valid and invalid, on a started app (its
lifespan runs: SQLite database, coordinator, in-process serial evaluator) and every response is
checked with all of schemathesis's built-in checks: no 5xx, a documented status code, content
type, headers and body conforming to the schema, 4xx for invalid input, and so on; and no body
may contain a Python traceback.

The service runs with tight ceilings, so a generated `POST /runs` or `POST /sweeps` that is
accepted queues a tiny run (at most 8 robots x 2 generations of 0.5 s) and anything bigger is
refused with 422. Before the examples run, one tiny run (in a sweep) is driven to completion, so
the boundary ids schemathesis tries (run 1, sweep 1, individual 0) reach real data: a curve,
individuals, a best robot and its replay, a finished event stream.

Run twice: without a token, and with `SOFTEVO_API_TOKEN` set and the right bearer header sent
(schemathesis then also checks that the state-changing operations refuse a missing or wrong
token).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import schemathesis
from hypothesis import HealthCheck, settings
from schemathesis.checks import (
    ignored_auth,
    missing_required_header,
    not_a_server_error,
    positive_data_acceptance,
)
from schemathesis.python import asgi

from softevo.api.app import create_app
from softevo.api.settings import Limits, Settings
from softevo.core.outputs import picture
from softevo.core.physics.evaluation import SerialEvaluator

pytestmark = pytest.mark.slow

TOKEN = "secret"
LIMITS = Limits(
    max_population=8,
    max_generations=2,
    max_voxels=8,
    max_duration=0.5,
    max_evaluations=16,
    max_sweep_runs=4,
)
#: The seeded run: 4 robots of 2x2x2 voxels, 2 generations of 0.5 s simulations.
TINY = {
    "preset": "quick",
    "population": 4,
    "generations": 2,
    "groups": 2,
    "sim": {"duration": 0.5, "settle_time": 0.1},
}


def _seed(app: object, token: str | None) -> None:
    """Sweep 1 with run 1, driven to completion (seconds: 8 tiny simulations)."""
    headers = {"Authorization": f"Bearer {token}"} if token else {}
    with asgi.get_client(app) as client:  # type: ignore[arg-type]
        created = client.post(
            "/sweeps", json={**TINY, "shapes": [[2, 2, 2]], "seeds": [1]}, headers=headers
        )
        assert created.status_code == 201, created.text
        deadline = time.monotonic() + 60
        while (status := client.get("/runs/1").json()["status"]) in ("queued", "running"):
            assert time.monotonic() < deadline, "the seeded run did not finish in 60 s"
            time.sleep(0.05)
        assert status == "completed", client.get("/runs/1").text


@pytest.fixture(params=[None, TOKEN], ids=["no-token", "token"])
def api_token(request: pytest.FixtureRequest) -> str | None:
    return request.param


@pytest.fixture
def api_schema(
    api_token: str | None, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> Iterator[schemathesis.BaseSchema]:
    """The app's schema; loading it starts the app's lifespan, stopped again at teardown."""
    # a server without ffmpeg: each generated MP4 request would encode a video (10 s of CPU a
    # run of the suite where CI has ffmpeg), and the schema's checks read the same either way
    monkeypatch.setattr(picture, "ffmpeg_available", lambda: False)
    app = create_app(
        Settings(
            database_url=f"sqlite:///{tmp_path / 's.db'}",
            api_token=api_token,
            max_running=1,
            poll_seconds=0.05,
            lease_seconds=5.0,
            limits=LIMITS,
        ),
        lambda _s: SerialEvaluator(),
    )
    try:
        loaded = schemathesis.openapi.from_asgi("/openapi.json", app)
        _seed(app, api_token)
        yield loaded
    finally:
        asgi.shutdown_lifespans()  # the app's shutdown: coordinator stopped, engine disposed


schema = schemathesis.pytest.from_fixture("api_schema")


@schema.parametrize()
@settings(
    max_examples=10,  # per operation and token setting (at 15 the file took 238 s, 2026-12-07)
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
def test_api_conforms_to_its_schema(case: schemathesis.Case, api_token: str | None) -> None:
    excluded = []
    if case.operation.method.upper() == "POST" and case.operation.path in ("/runs", "/sweeps"):
        # A schema-valid run config is still refused (422, naming the field) when it is over the
        # service's ceilings (a runtime setting, here tiny) or inconsistent across fields
        # (cube-springs needs shape 1x1x1, immigrants must leave room for children, ...), which
        # no static schema can state.
        excluded.append(positive_data_acceptance)
    if case.operation.path == "/runs/{run_id}/best/replay.{format}":
        # A valid request for an MP4 is a documented 501 on a server without ffmpeg (this one,
        # whatever the machine has: `api_schema`; MP4s are test_pictures.py's).
        excluded += [positive_data_acceptance, not_a_server_error]
    if api_token:
        headers = {"Authorization": f"Bearer {api_token}"}
        response = case.call_and_validate(headers=headers, excluded_checks=excluded)
    else:
        # Without a token the service deliberately serves everyone: the schema's bearer scheme
        # is not enforced, so the two authentication checks do not apply.
        excluded += [ignored_auth, missing_required_header]
        response = case.call_and_validate(excluded_checks=excluded)
    assert b"Traceback" not in response.content  # bytes: the figures are PNG
