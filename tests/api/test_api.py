"""Every endpoint through the real app (TestClient, coordinator running), and every error."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import event

from softevo.cli import main

SMALL = {"preset": "quick", "seed": 1, "population": 6, "generations": 3}


def wait_for(client: TestClient, run_id: int, statuses: tuple[str, ...], timeout: float = 60):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        run = client.get(f"/runs/{run_id}").json()
        if run["status"] in statuses:
            return run
        time.sleep(0.05)
    raise AssertionError(f"run {run_id} did not reach {statuses}: {run}")


def start(client: TestClient, **overrides: object) -> int:
    response = client.post("/runs", json={**SMALL, **overrides})
    assert response.status_code == 201, response.text
    assert response.headers["location"] == f"/runs/{response.json()['id']}"
    return response.json()["id"]


def test_run_lifecycle_and_results(client: TestClient) -> None:
    run_id = start(client)
    run = wait_for(client, run_id, ("completed",))
    assert run["progress"]["generation"] == run["progress"]["generations"] == 3
    assert run["progress"]["fitness_saved"] == 18
    assert run["progress"]["evaluations"] + run["progress"]["saved"] == 18
    assert run["progress"]["best_fitness"] > 0 and run["finished_at"] is not None
    assert run["config"]["population"] == 6 and run["config"]["preset"] == "quick"

    curve = client.get(f"/runs/{run_id}/curve").json()
    assert curve["run_id"] == run_id
    assert [row["generation"] for row in curve["generations"]] == [0, 1, 2]
    last = curve["generations"][-1]
    assert last["best_so_far"] == run["progress"]["best_fitness"]
    assert last["min"] <= last["median"] <= last["best"] <= last["best_so_far"]

    text = client.get(f"/runs/{run_id}/curve", params={"format": "csv"})
    assert text.headers["content-type"].startswith("text/csv")
    lines = text.text.strip().splitlines()
    assert lines[0].startswith("generation,best,mean,median,min,best_so_far,diversity")
    assert len(lines) == 4 and float(lines[-1].split(",")[5]) == last["best_so_far"]

    page = client.get(f"/runs/{run_id}/individuals", params={"generation": 1}).json()
    assert page["total"] == 6 and [item["index"] for item in page["items"]] == list(range(6))
    assert all(item["status"] in ("evaluated", "cached") for item in page["items"])
    everything = client.get(f"/runs/{run_id}/individuals", params={"limit": 5, "offset": 15})
    assert everything.json()["total"] == 18 and len(everything.json()["items"]) == 3

    detail = client.get(f"/runs/{run_id}/individuals/7").json()
    assert (detail["generation"], detail["index"]) == (1, 1)
    assert detail["robot"]["format"] == "softevo.robot/1" and detail["genome"]["discrete"]

    best = client.get(f"/runs/{run_id}/best").json()
    assert best["format"] == "softevo.robot/1" and best["shape"] == [3, 3, 3]
    replay = client.get(f"/runs/{run_id}/best/replay", params={"fps": 10}).json()
    assert replay["fitness"] == run["progress"]["best_fitness"]
    assert len(replay["frames"]) >= 10 and replay["springs"]
    assert replay["speed"] == pytest.approx(replay["fitness"], rel=1e-9)
    assert len(replay["phase"]) == len(replay["springs"]) == len(replay["stiffness"])

    # any individual replays, with the fitness it was given
    one = client.get(f"/runs/{run_id}/individuals/7/replay", params={"fps": 10}).json()
    assert one["number"] == 7 and one["generation"] == 1 and one["robot"] == detail["robot"]
    if detail["fitness"] is not None:
        assert one["speed"] == pytest.approx(detail["fitness"], rel=1e-9)
    assert client.get(f"/runs/{run_id}/individuals/999/replay").status_code == 404
    # and the figures come as PNG
    for kind in ("curve", "population", "diversity"):
        png = client.get(f"/runs/{run_id}/figures/{kind}.png")
        assert png.status_code == 200 and png.headers["content-type"] == "image/png"
        assert png.content[:8] == b"\x89PNG\r\n\x1a\n" and len(png.content) > 10_000
    assert client.get(f"/runs/{run_id}/figures/other.png").status_code == 422
    assert client.get("/runs/999/figures/curve.png").status_code == 404


def test_replays_are_bounded_and_remembered(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A replay is simulated on a GET, so its frames are capped (fps lowered to fit, and said)
    and a repeated request is served from memory, not simulated again."""
    from softevo.api import replay

    run_id = start(client)
    wait_for(client, run_id, ("completed",))
    simulated: list[float] = []
    real = replay._simulate
    monkeypatch.setattr(
        replay,
        "_simulate",
        lambda *a: simulated.append(a[1]) or real(*a),  # type: ignore[func-returns-value]
    )
    monkeypatch.setattr(replay, "_cache", type(replay._cache)())
    monkeypatch.setattr(replay, "MAX_POSITIONS", 2000)
    capped = client.get(f"/runs/{run_id}/best/replay", params={"fps": 120}).json()
    masses = len(capped["frames"][0])
    assert len(capped["frames"]) * masses <= 2000 + masses
    assert capped["fps"] < 120
    assert capped["times"][1] == pytest.approx(1 / capped["fps"])
    again = client.get(f"/runs/{run_id}/best/replay", params={"fps": 120}).json()
    assert again == capped and len(simulated) == 1
    monkeypatch.setattr(replay, "MAX_POSITIONS", 10**9)  # another server's setting:
    replay._cache.clear()  # its replays are its own
    full = client.get(f"/runs/{run_id}/best/replay", params={"fps": 120}).json()
    assert full["fps"] == pytest.approx(120, rel=0.05) and len(simulated) == 2
    assert full["speed"] == capped["speed"]  # the same simulation, only recorded more often


def test_a_run_through_the_api_has_the_curve_of_softevo_run(
    client: TestClient, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run_id = start(client, seed=5, population=8, generations=4)
    run = wait_for(client, run_id, ("completed",))
    argv = [
        "run",
        "--preset",
        "quick",
        "--seed",
        "5",
        "--population",
        "8",
        "--generations",
        "4",
        "--workers",
        "1",
        "--json",
        "--out",
        str(tmp_path / "out"),
    ]
    assert main(argv) == 0
    printed = json.loads(capsys.readouterr().out)
    assert client.get(f"/runs/{run_id}/curve").json()["generations"] == printed["generations"]
    assert run["progress"]["evaluations"] == printed["evaluations"]
    assert run["progress"]["saved"] == printed["saved"]
    assert client.get(f"/runs/{run_id}/best").json() == printed["best"]["robot"]


def test_events_stream_one_per_generation_then_end(client: TestClient) -> None:
    run_id = start(client)
    events = []
    with client.stream("GET", f"/runs/{run_id}/events") as stream:
        name = None
        for line in stream.iter_lines():
            if line.startswith("event: "):
                name = line.removeprefix("event: ")
            elif line.startswith("data: "):
                events.append((name, json.loads(line.removeprefix("data: "))))
    generations = [data["generation"] for name, data in events if name == "generation"]
    assert generations == [0, 1, 2]
    assert events[-1][0] == "end" and events[-1][1]["status"] == "completed"
    # a client that reconnects with Last-Event-ID gets only what came after
    with client.stream("GET", f"/runs/{run_id}/events", headers={"Last-Event-ID": "1"}) as s:
        body = "".join(s.iter_text())
    assert body.count("event: generation") == 1 and "id: 2" in body
    # a Last-Event-ID that is not a plain integer counts as none: the whole stream, never a 500
    for hostile in ("--5", "\xb2", "9" * 5000, "1e3", " 1", "-0x1"):
        headers = {"Last-Event-ID": hostile.encode("latin-1")}
        with client.stream("GET", f"/runs/{run_id}/events", headers=headers) as s:
            assert s.status_code == 200
            assert "".join(s.iter_text()).count("event: generation") == 3, hostile


def test_list_runs_paginates_and_filters(client: TestClient) -> None:
    first, second = start(client), start(client, seed=2)
    wait_for(client, first, ("completed",))
    wait_for(client, second, ("completed",))
    page = client.get("/runs", params={"limit": 1}).json()
    assert page["total"] == 2 and [run["id"] for run in page["items"]] == [second]
    assert client.get("/runs", params={"status": "completed"}).json()["total"] == 2
    assert client.get("/runs", params={"status": "queued"}).json()["total"] == 0
    assert client.get("/runs", params={"status": "bogus"}).status_code == 422
    assert client.get("/runs", params={"limit": 10_000}).status_code == 422


def test_cancel_stops_at_once_and_keeps_results(client: TestClient) -> None:
    run_id = start(client, generations=500)
    deadline = time.monotonic() + 30
    while client.get(f"/runs/{run_id}").json()["progress"]["generation"] < 1:
        assert time.monotonic() < deadline
        time.sleep(0.05)
    cancelled = client.post(f"/runs/{run_id}/cancel")
    assert cancelled.status_code == 200 and cancelled.json()["status"] == "cancelled"
    committed = len(client.get(f"/runs/{run_id}/curve").json()["generations"])
    coordinator = client.app.state.coordinator  # type: ignore[attr-defined]
    assert coordinator.join(run_id, 30)  # its driver has stopped: nothing more can be written
    after = client.get(f"/runs/{run_id}").json()
    assert after["status"] == "cancelled" and committed >= 1
    assert len(client.get(f"/runs/{run_id}/curve").json()["generations"]) == committed
    again = client.post(f"/runs/{run_id}/cancel")
    assert again.status_code == 409 and "cancelled" in again.json()["detail"]


def test_runs_beyond_the_bound_wait_queued(make_client: Callable[..., TestClient]) -> None:
    client = make_client(max_running=1)
    first = start(client, generations=200)
    second = start(client, seed=2)
    deadline = time.monotonic() + 30
    while client.get(f"/runs/{first}").json()["status"] != "running":
        assert time.monotonic() < deadline
        time.sleep(0.05)
    coordinator = client.app.state.coordinator  # type: ignore[attr-defined]
    assert coordinator.wait_ticks(3, 30)  # the scheduler looked again, and again left it waiting
    assert client.get(f"/runs/{second}").json()["status"] == "queued"
    assert client.get("/healthz").json()["coordinator"]["driving"] == [first]
    client.post(f"/runs/{first}/cancel")
    assert wait_for(client, second, ("completed",))["status"] == "completed"


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({"preset": "nope"}, ["body", "preset"]),
        ({"population": "many"}, ["body", "population"]),
        ({"population": 1}, ["body", "population"]),
        ({"population": 5000}, ["body", "population"]),
        ({"generations": 10**6}, ["body", "generations"]),
        ({"shape": [11, 10, 10]}, ["body", "shape"]),
        ({"shape": [0, 3, 3]}, ["body", "shape"]),
        ({"sim": {"duration": 1000.0}}, ["body", "sim", "duration"]),
        ({"sim": {"dt": 1e-6}}, ["body", "sim", "dt"]),
        ({"sim": {"dt": -1.0}}, ["body", "sim", "dt"]),
        ({"sim": {"jelly": 1.0}}, ["body", "sim", "jelly"]),
        ({"colour": "red"}, ["body", "colour"]),
        ({"seed": -1}, ["body", "seed"]),
        ({"population": 1000, "generations": 5000}, ["body", "generations"]),
        # strict types: no bool or string for a number, no float for a count
        ({"seed": True}, ["body", "seed"]),
        ({"seed": "5"}, ["body", "seed"]),
        ({"population": 2.0}, ["body", "population"]),
        ({"shape": [True, 1, 1]}, ["body", "shape", 0]),
        ({"elitism": 1}, ["body", "elitism"]),
        ({"sim": {"duration": True}}, ["body", "sim", "duration"]),
    ],
)
def test_bad_configs_are_refused_naming_the_field(
    client: TestClient, body: dict, field: list[str]
) -> None:
    response = client.post("/runs", json={"preset": "quick", **body})
    assert response.status_code == 422, response.text
    locations = [error["loc"] for error in response.json()["detail"]]
    assert any(location[: len(field)] == field for location in locations), locations
    assert client.get("/runs").json()["total"] == 0  # nothing was queued


def test_malformed_json_is_a_422_not_a_500(client: TestClient) -> None:
    response = client.post(
        "/runs", content=b"{not json", headers={"content-type": "application/json"}
    )
    assert response.status_code == 422 and "detail" in response.json()


@pytest.mark.parametrize(
    "path",
    [
        "/runs/999",
        "/runs/999/curve",
        "/runs/999/individuals",
        "/runs/999/individuals/0",
        "/runs/999/best",
        "/runs/999/best/replay",
        "/runs/999/events",
        "/sweeps/999",
    ],
)
def test_unknown_ids_are_404_json(client: TestClient, path: str) -> None:
    response = client.get(path)
    assert response.status_code == 404
    assert "999 not found" in response.json()["detail"]
    assert client.post("/runs/999/cancel").status_code == 404


def test_best_before_any_generation_is_404_and_individual_out_of_range(
    make_client: Callable[..., TestClient],
) -> None:
    client = make_client(max_running=1)
    blocker = start(client, generations=300)
    queued = start(client)
    assert client.get(f"/runs/{queued}/best").status_code == 404
    assert "no evaluated generation" in client.get(f"/runs/{queued}/best").json()["detail"]
    assert client.get(f"/runs/{queued}/individuals/0").status_code == 404
    client.post(f"/runs/{blocker}/cancel")
    client.post(f"/runs/{queued}/cancel")


def test_token_guards_every_state_change(make_client: Callable[..., TestClient]) -> None:
    client = make_client(api_token="s3cret")
    for path, body in (("/runs", SMALL), ("/sweeps", {**SMALL, "shapes": [[2, 2, 2]]})):
        missing = client.post(path, json=body)
        assert missing.status_code == 401 and missing.headers["www-authenticate"] == "Bearer"
        wrong = client.post(path, json=body, headers={"Authorization": "Bearer nope"})
        assert wrong.status_code == 403 and "wrong" in wrong.json()["detail"]
    assert client.get("/runs").json()["total"] == 0
    ok = client.post("/runs", json=SMALL, headers={"Authorization": "Bearer s3cret"})
    assert ok.status_code == 201
    run_id = ok.json()["id"]
    assert client.get(f"/runs/{run_id}").status_code == 200  # reads need no token
    assert client.post(f"/runs/{run_id}/cancel").status_code == 401
    assert client.post("/runs/999/cancel").status_code == 401  # nothing leaks without a token


def test_sweep_over_boxes_and_seeds(client: TestClient) -> None:
    body = {"preset": "quick", "population": 4, "generations": 2, "shapes": [[2, 2, 2], [3, 1, 2]]}
    response = client.post("/sweeps", json={**body, "seeds": [1, 2]})
    assert response.status_code == 201, response.text
    sweep = response.json()
    assert [box["shape"] for box in sweep["boxes"]] == [[2, 2, 2], [3, 1, 2]]
    run_ids = [run_id for box in sweep["boxes"] for run_id in box["run_ids"]]
    assert len(run_ids) == 4
    for run_id in run_ids:
        wait_for(client, run_id, ("completed",))
    done = client.get(f"/sweeps/{sweep['id']}").json()
    assert done["status"] == "completed"
    for box in done["boxes"]:
        runs = [client.get(f"/runs/{i}").json() for i in box["run_ids"]]
        bests = [run["progress"]["best_fitness"] for run in runs]
        assert box["completed"] == 2
        assert box["best_mean"] == pytest.approx(sum(bests) / 2)
        assert box["best_min"] == min(bests) and box["best_max"] == max(bests)
        assert sorted(run["seed"] for run in runs) == [1, 2]


def test_sweep_with_one_bad_box_queues_nothing(client: TestClient) -> None:
    response = client.post("/sweeps", json={"preset": "quick", "shapes": [[2, 2, 2], [11, 10, 10]]})
    assert response.status_code == 422
    assert response.json()["detail"][0]["loc"][:3] == ["body", "shapes", "1"]
    assert client.get("/runs").json()["total"] == 0


def test_default_sweep_is_the_papers_nine_boxes(client: TestClient) -> None:
    response = client.post("/sweeps", json={"preset": "paper-voxel", "seeds": [1]})
    assert response.status_code == 201
    shapes = [box["shape"] for box in response.json()["boxes"]]
    assert len(shapes) == 9 and [3, 3, 6] in shapes and [9, 9, 2] in shapes
    for box in response.json()["boxes"]:
        client.post(f"/runs/{box['run_ids'][0]}/cancel")


def test_presets_health_and_openapi(client: TestClient) -> None:
    presets = {p["name"]: p for p in client.get("/presets").json()}
    assert {"paper-cube", "paper-voxel", "voxel-plus", "quick"} <= set(presets)
    assert presets["paper-voxel"]["settings"]["population"] == 25
    health = client.get("/healthz")
    assert health.status_code == 200
    assert health.json()["database"] == "ok" and health.json()["redis"] == "not configured"
    schema = client.get("/openapi.json").json()
    for path in ("/runs", "/runs/{run_id}/curve", "/runs/{run_id}/events", "/sweeps", "/presets"):
        assert path in schema["paths"]
    assert client.get("/docs").status_code == 200


def test_health_reports_redis_down(make_client: Callable[..., TestClient]) -> None:
    client = make_client(redis_url="redis://127.0.0.1:1/0")
    response = client.get("/healthz")
    assert response.status_code == 503
    assert response.json()["redis"].startswith("down")


def test_readers_and_writers_never_fail_while_a_run_writes(
    make_client: Callable[..., TestClient],
) -> None:
    """SQLite in WAL mode with BEGIN IMMEDIATE: no 'database is locked', no 5xx."""
    from concurrent.futures import ThreadPoolExecutor

    client = make_client(batch_size=1, max_running=2)
    run_id = start(client, generations=30)
    paths = [f"/runs/{run_id}", f"/runs/{run_id}/curve", f"/runs/{run_id}/individuals", "/runs"]

    def hammer(worker: int) -> list[int]:
        codes = []
        deadline = time.monotonic() + 3
        while time.monotonic() < deadline:
            codes.append(client.get(paths[worker % len(paths)]).status_code)
            if worker == 0 and len(codes) % 20 == 0:  # a second writer, now and then
                created = client.post("/runs", json={**SMALL, "generations": 1})
                codes.append(created.status_code - 1 if created.status_code == 201 else 0)
        return codes

    with ThreadPoolExecutor(4) as pool:
        codes = [code for result in pool.map(hammer, range(4)) for code in result]
    assert len(codes) > 50 and set(codes) == {200}, sorted(set(codes))
    assert client.get(f"/runs/{run_id}").json()["status"] in ("running", "completed")
    client.post(f"/runs/{run_id}/cancel")


def test_reads_never_load_the_ga_state(client: TestClient) -> None:
    """The GA state (two populations of JSON) is the coordinator's: no read route selects it,
    so a listing of large runs costs what their summaries cost; the archive of a run with
    descriptors is read alone."""
    run_id = start(client, descriptors=["voxels"], bins=[4])
    wait_for(client, run_id, ("completed",))
    statements: list[str] = []

    def seen(_conn: Any, _cursor: Any, statement: str, *_args: Any) -> None:
        statements.append(statement)

    engine = client.app.state.db.engine  # type: ignore[attr-defined]
    event.listen(engine, "before_cursor_execute", seen)
    try:
        for path in (
            "/runs",
            f"/runs/{run_id}",
            f"/runs/{run_id}/curve",
            f"/runs/{run_id}/individuals",
            f"/runs/{run_id}/best",
            f"/runs/{run_id}/archive",
            f"/runs/{run_id}/archive?robots=true",
        ):
            assert client.get(path).status_code == 200, path
        with client.stream("GET", f"/runs/{run_id}/events") as stream:
            assert "event: end" in "".join(stream.iter_text())
    finally:
        event.remove(engine, "before_cursor_execute", seen)
    selects = [s for s in statements if s.lstrip().upper().startswith("SELECT")]
    assert selects and not [s for s in selects if "ga_state" in s]
    archive = client.get(f"/runs/{run_id}/archive").json()
    assert archive["cells"] and archive["coverage"] > 0  # read from its own column


def test_replays_share_fps_buckets_run_two_at_once_and_keep_to_a_byte_budget(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Any fps does not force a new simulation (29 and 31 share the 30 bucket); a third replay
    while two are simulating is a 503 with Retry-After, never a request thread waiting; the
    cache keeps to its bytes."""
    import threading

    from softevo.api import replay

    run_id = start(client)
    wait_for(client, run_id, ("completed",))
    monkeypatch.setattr(replay, "_cache", type(replay._cache)())
    calls: list[float] = []
    gate, real = threading.Event(), replay._simulate

    def slow(robot: Any, fps: float) -> dict[str, Any]:
        calls.append(fps)
        if fps < 1:  # the 0.1 and 0.2 buckets wait for the gate: two simulations in progress
            gate.wait(30)
        return real(robot, fps)

    monkeypatch.setattr(replay, "_simulate", slow)
    url = f"/runs/{run_id}/best/replay"
    first = client.get(url, params={"fps": 29}).json()
    assert client.get(url, params={"fps": 31}).json() == first and calls == [30.0]
    others = [TestClient(client.app, client=(f"10.0.0.{n}", 50000)) for n in (1, 2)]  # a slot each
    held = [
        threading.Thread(target=other.get, args=(url,), kwargs={"params": {"fps": f}})
        for other, f in zip(others, (0.1, 0.2), strict=True)
    ]
    for thread in held:
        thread.start()
    deadline = time.monotonic() + 30
    while len(calls) < 3:
        assert time.monotonic() < deadline
        time.sleep(0.01)
    busy = client.get(url, params={"fps": 5})
    assert busy.status_code == 503 and busy.headers["Retry-After"] == "2"
    assert "replays are being simulated" in busy.json()["detail"]
    gate.set()
    for thread in held:
        thread.join(30)
    assert client.get(url, params={"fps": 5}).status_code == 200  # a slot is free again
    monkeypatch.setattr(replay, "CACHED_BYTES", 1)  # room for the newest only
    client.get(url, params={"fps": 10})
    assert len(replay._cache) == 1


def test_event_clients_share_one_watcher_and_are_capped(
    make_client: Callable[..., TestClient],
) -> None:
    """Ten clients following a run read the database as one does (one watcher per run); past
    SOFTEVO_MAX_EVENT_CLIENTS a new stream is a 503."""
    import threading

    from softevo.api import events
    from softevo.api.settings import Limits

    client = make_client(limits=Limits(max_event_clients=10))
    run_id = start(client, generations=40)
    statements: list[str] = []

    def seen(_conn: Any, _cursor: Any, statement: str, *_args: Any) -> None:
        if "FROM generations" in statement:
            statements.append(statement)

    engine = client.app.state.db.engine  # type: ignore[attr-defined]
    event.listen(engine, "before_cursor_execute", seen)
    ends: list[int] = []

    def follow() -> None:
        with client.stream("GET", f"/runs/{run_id}/events") as stream:
            text = "".join(stream.iter_text())
        ends.append(text.count("event: generation") if "event: end" in text else -1)

    followers = [threading.Thread(target=follow) for _ in range(10)]
    started = time.monotonic()
    for thread in followers:
        thread.start()
    deadline = time.monotonic() + 30
    while client.app.state.watches.clients < 10:  # type: ignore[attr-defined]
        assert time.monotonic() < deadline
        time.sleep(0.01)
    refused = client.get(f"/runs/{run_id}/events")
    assert refused.status_code == 503 and "SOFTEVO_MAX_EVENT_CLIENTS" in refused.json()["detail"]
    for thread in followers:
        thread.join(120)
    elapsed = time.monotonic() - started
    event.remove(engine, "before_cursor_execute", seen)
    assert ends == [40] * 10  # every client saw every generation, then the end
    polls = elapsed / events.POLL_SECONDS + 5  # one watcher's reads, at most
    # the coordinator's own writes and reads of `generations` come on top; ten pollers would
    # read ten times as often
    assert len(statements) < 2 * polls, (len(statements), polls)
