"""Hostile input: oversized and malformed bodies, runaway settings, a full queue, and the token.

Each case must be refused with a clear JSON error (no 5xx, no stack trace) before anything is
queued. The schema-wide fuzzing is `test_schemathesis.py`; this file does what a fuzzer would not
think of: bodies over the limit with and without a declared length, nesting deep enough to break
a recursive parser, numbers too large for any type.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from softevo.api import store
from softevo.api.db import Database
from softevo.api.settings import Limits
from softevo.core.config import resolve
from softevo.core.evolution import CURVE_COLUMNS, Evolution
from softevo.core.physics.evaluation import SerialEvaluator

SMALL = {"preset": "quick", "seed": 1, "population": 6, "generations": 3}
JSON = {"content-type": "application/json"}


def no_trace(text: str) -> None:
    assert "Traceback" not in text and 'File "' not in text, text


def run_count(client: TestClient) -> int:
    return client.get("/runs").json()["total"]


def test_a_body_over_the_limit_is_refused_with_or_without_a_length(
    make_client: Callable[..., TestClient],
) -> None:
    client = make_client(limits=Limits(max_body_bytes=4096))
    declared = client.post("/runs", content=b" " * 5000, headers=JSON)
    assert declared.status_code == 413, declared.text
    assert "SOFTEVO_MAX_BODY_BYTES" in declared.json()["detail"]

    def chunks() -> Iterator[bytes]:  # no Content-Length: sent chunked
        for _ in range(10):
            yield b" " * 1000

    chunked = client.post("/runs", content=chunks(), headers=JSON)
    assert chunked.status_code == 413, chunked.text
    assert "4096" in chunked.json()["detail"]
    padded = client.post("/runs", content=b'{"preset": "quick"}' + b" " * 4000, headers=JSON)
    assert padded.status_code == 201, padded.text  # within the limit: served as usual
    client.post(f"/runs/{padded.json()['id']}/cancel")
    assert run_count(client) == 1


@pytest.mark.parametrize(
    ("body", "status", "words"),
    [
        ("[" * 100_000 + "]" * 100_000, 400, "parsing the body"),
        ('{"preset": "quick", "seed": ' + "9" * 5000 + "}", 400, "parsing the body"),
        ('{"preset": "quick", "seed": NaN}', 422, "seed"),
        ('{"preset": "quick", "sim": {"duration": Infinity}}', 422, "sim"),
        ('{"preset": "quick", "shape": {"a": [[[]]]}}', 422, "shape"),
        ('{"preset": "quick", "population": "many"}', 422, "population"),
        ('{"preset": ["quick"]}', 422, "preset"),
        ('"just a string"', 422, "body"),
        ("{'preset': 'quick'}", 422, "JSON decode error"),
    ],
)
def test_malformed_bodies_get_a_clear_error_and_queue_nothing(
    client: TestClient, body: str, status: int, words: str
) -> None:
    response = client.post("/runs", content=body.encode(), headers=JSON)
    assert response.status_code == status, response.text
    assert words in response.text
    no_trace(response.text)
    assert run_count(client) == 0


@pytest.mark.parametrize(
    ("headers", "got"),
    [
        ({}, "no Content-Type"),
        ({"content-type": "text/plain"}, "'text/plain'"),
        (
            {"content-type": "application/x-www-form-urlencoded"},
            "'application/x-www-form-urlencoded'",
        ),
    ],
)
@pytest.mark.parametrize("path", ["/runs", "/sweeps"])
def test_a_body_not_sent_as_json_names_the_content_type_to_send(
    client: TestClient, headers: dict[str, str], got: str, path: str
) -> None:
    """A client that forgot the header hears what to send, not pydantic's "a valid dictionary"."""
    response = client.post(path, content=b'{"preset": "quick"}', headers=headers)
    assert response.status_code == 422, response.text
    (error,) = response.json()["detail"]
    assert error["loc"] == ["body"] and error["type"] == "content_type"
    assert "Content-Type: application/json" in error["msg"] and got in error["msg"]
    assert run_count(client) == 0
    sent = client.post(path, content=b'{"preset": "quick"}', headers=JSON)  # the same, declared
    assert sent.status_code == 201, sent.text


@pytest.mark.parametrize(
    ("override", "field"),
    [
        ({"shape": [100, 100, 100]}, "shape"),
        ({"population": 10**6}, "population"),
        ({"generations": 10**7}, "generations"),
        ({"sim": {"duration": 1e6}}, "sim"),
        ({"sim": {"dt": 1e-12}}, "sim"),
        ({"population": 1000, "generations": 10_000}, "generations"),
        ({"algorithm": "annealing"}, "algorithm"),
    ],
)
def test_settings_that_would_explode_are_refused_before_queuing(
    client: TestClient, override: dict, field: str
) -> None:
    response = client.post("/runs", json={**SMALL, **override})
    assert response.status_code == 422, response.text
    assert response.json()["detail"][0]["loc"][:2] == ["body", field]
    assert run_count(client) == 0


def test_a_wrong_method_lists_the_allowed_ones(client: TestClient) -> None:
    assert client.delete("/runs/1").headers["allow"] == "GET"
    assert client.put("/runs").headers["allow"] == "GET, POST"
    assert client.get("/runs/1/cancel").headers["allow"] == "POST"


def test_pagination_limits_are_capped(client: TestClient) -> None:
    assert client.get("/runs", params={"limit": 10_000}).status_code == 422
    run_id = client.post("/runs", json=SMALL).json()["id"]
    too_many = client.get(f"/runs/{run_id}/individuals", params={"limit": 10**6})
    assert too_many.status_code == 422 and "limit" in too_many.text


def test_a_full_queue_refuses_with_429_and_queues_nothing(
    make_client: Callable[..., TestClient],
) -> None:
    client = make_client(limits=Limits(max_queued=2))
    body = {"preset": "quick", "population": 6, "shapes": [[2, 2, 2], [3, 2, 2], [2, 3, 2]]}
    response = client.post("/sweeps", json=body)
    assert response.status_code == 429, response.text
    assert response.headers["retry-after"] == "30"
    assert "SOFTEVO_MAX_QUEUED" in response.json()["detail"]
    assert run_count(client) == 0


@pytest.mark.slow
@pytest.mark.fault
def test_a_queue_filled_past_its_bound_over_http_then_drained(
    make_client: Callable[..., TestClient],
) -> None:
    """Two API processes (two apps, each with its coordinator) on one database, a bound of 2
    queued runs, and 12 POSTs at once from two threads: the bound holds at every moment, every
    refusal is a 429 that queues nothing, every accepted run completes with the curve it has in
    process, and once the queue drains a new run is accepted again."""
    limits = Limits(max_queued=2)
    apps = [make_client(max_running=1, limits=limits) for _ in range(2)]
    request = {"preset": "quick", "population": 6, "generations": 5, "sim": {"duration": 1.0}}
    answers: list[tuple[int, Any]] = []
    queued_seen: list[int] = []
    lock = threading.Lock()

    def post(client: TestClient, seeds: range) -> None:
        for seed in seeds:
            response = client.post("/runs", json={**request, "seed": seed})
            with lock:
                answers.append((seed, response))

    threads = [
        threading.Thread(target=post, args=(apps[0], range(0, 6))),
        threading.Thread(target=post, args=(apps[1], range(6, 12))),
    ]
    started = time.monotonic()
    for thread in threads:
        thread.start()
    while any(thread.is_alive() for thread in threads):
        queued_seen.append(apps[0].get("/runs", params={"status": "queued"}).json()["total"])
    for thread in threads:
        thread.join()
    accepted = {seed: r.json()["id"] for seed, r in answers if r.status_code == 201}
    refused = [r for _, r in answers if r.status_code != 201]
    codes = [r.status_code for _, r in answers]
    assert len(answers) == 12 and len(accepted) >= 2 and refused, codes
    for response in refused:
        assert response.status_code == 429, response.text
        assert response.headers["retry-after"] == "30"
        assert "SOFTEVO_MAX_QUEUED" in response.json()["detail"]
        no_trace(response.text)
    assert max(queued_seen) <= 2, queued_seen
    assert run_count(apps[0]) == len(accepted)  # a refusal queued nothing
    # room again once the queue drains: the next POST is accepted
    while (again := apps[0].post("/runs", json={**request, "seed": 99})).status_code == 429:
        assert time.monotonic() - started < 60, "the queue never drained"
        time.sleep(0.1)
    assert again.status_code == 201, again.text
    room = time.monotonic() - started
    accepted[99] = again.json()["id"]
    deadline = time.monotonic() + 120
    for seed, run_id in accepted.items():
        while (run := apps[0].get(f"/runs/{run_id}").json())["status"] in ("queued", "running"):
            assert time.monotonic() < deadline, run
            time.sleep(0.05)
        assert run["status"] == "completed", run
        evolution = Evolution.start(resolve({**request, "seed": seed}))
        evolution.run(SerialEvaluator())
        curve = apps[1].get(f"/runs/{run_id}/curve").json()["generations"]
        columns = [{c: g[c] for c in CURVE_COLUMNS} for g in curve]
        assert columns == [{c: g[c] for c in CURVE_COLUMNS} for g in evolution.curve()]
    print(
        f"12 POSTs at once against a bound of 2: {len(accepted) - 1} accepted, {len(refused)} "
        f"refused with 429, at most {max(queued_seen)} queued ({len(queued_seen)} samples); "
        f"room again {room:.2f} s after the burst began; all {len(accepted)} runs completed "
        f"{time.monotonic() - started:.2f} s after it, each with its in-process curve"
    )


def test_the_queue_bound_is_counted_in_the_write(db: Database) -> None:
    """On both databases: the bound counts queued runs only, and a sweep is all or nothing."""
    config = resolve(SMALL)
    first = store.create_run(db, config, max_queued=2)
    store.create_run(db, config, max_queued=2)
    with pytest.raises(store.QueueFullError, match="2 runs are waiting"):
        store.create_run(db, config, max_queued=2)
    with pytest.raises(store.QueueFullError):
        store.create_sweep(db, {}, [config, config], max_queued=3)
    assert store.list_runs(db, None, 0, 10)[1] == 2
    store.cancel_run(db, first.id)  # one leaves the queue: there is room again
    store.create_run(db, config, max_queued=2)


STATE_CHANGING = {"POST", "PUT", "PATCH", "DELETE"}


def test_every_state_changing_endpoint_needs_the_token(
    make_client: Callable[..., TestClient],
) -> None:
    """Found from the app's own routes, so an endpoint added later is covered too."""
    client = make_client(api_token="s3cret")
    routes = [
        (method.upper(), path)
        for path, operations in client.get("/openapi.json").json()["paths"].items()
        for method in operations
        if method.upper() in STATE_CHANGING
    ]
    assert ("POST", "/runs") in routes and ("POST", "/runs/{run_id}/cancel") in routes
    for method, path in routes:
        url = path.replace("{run_id}", "1").replace("{sweep_id}", "1")
        missing = client.request(method, url, json=SMALL)
        assert missing.status_code == 401, (method, path, missing.text)
        wrong = client.request(method, url, json=SMALL, headers={"Authorization": "Bearer x"})
        assert wrong.status_code == 403, (method, path, wrong.text)
        no_trace(wrong.text)
    assert run_count(client) == 0


def test_healthz_shows_internals_only_with_the_token(
    make_client: Callable[..., TestClient],
) -> None:
    client = make_client(api_token="s3cret")
    anyone = client.get("/healthz").json()
    assert anyone["status"] == "ok" and anyone["coordinator"] is None
    guess = client.get("/healthz", headers={"Authorization": "Bearer guess"}).json()
    assert guess["coordinator"] is None
    trusted = client.get("/healthz", headers={"Authorization": "Bearer s3cret"}).json()
    owner = trusted["coordinator"]["owner"]
    assert owner.count(":") == 2 and owner not in client.get("/healthz").text


def test_errors_say_nothing_about_other_runs(make_client: Callable[..., TestClient]) -> None:
    client = make_client(api_token="s3cret")
    auth = {"Authorization": "Bearer s3cret"}
    secret = client.post("/runs", json={**SMALL, "seed": 424242}, headers=auth).json()["id"]
    other = client.post("/runs", json=SMALL, headers=auth).json()["id"]
    absent = other + 1000
    for response in (
        client.get(f"/runs/{absent}"),
        client.get(f"/runs/{absent}/curve"),
        client.post(f"/runs/{absent}/cancel", headers=auth),
        client.post(f"/runs/{secret}/cancel", headers={"Authorization": "Bearer guess"}),
        client.post(f"/runs/{absent}/cancel", headers={"Authorization": "Bearer guess"}),
    ):
        assert response.status_code in (403, 404), response.text
        detail = response.json()["detail"]
        assert detail in (f"run {absent} not found", "wrong bearer token"), detail
    # a wrong token gets the same answer whether the run exists or not
    guess = {"Authorization": "Bearer guess"}
    assert (
        client.post(f"/runs/{secret}/cancel", headers=guess).json()
        == client.post(f"/runs/{absent}/cancel", headers=guess).json()
    )
    for run_id in (secret, other):
        client.post(f"/runs/{run_id}/cancel", headers=auth)
