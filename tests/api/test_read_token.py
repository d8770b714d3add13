"""Closed reads (SOFTEVO_PROTECT_READS=1): every GET but /healthz and the dashboard's page needs
the token, as a bearer header or the dashboard's cookie; a cookie never opens a write; off by
default; the Python client and the dashboard's JavaScript send the token with every request."""

from __future__ import annotations

import json
import shutil
import subprocess
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from fastapi.testclient import TestClient

from softevo import client as client_module
from softevo.api.app import create_app
from softevo.api.settings import Settings
from softevo.core.physics.evaluation import SerialEvaluator

STATIC = Path(__file__).resolve().parents[2] / "api" / "dashboard" / "static"
READS = (
    "/runs",
    "/runs/1",
    "/runs/1/curve",
    "/runs/1/archive",
    "/sweeps",
    "/presets",
    "/runs/1/figures/curve.png",
    "/runs/1/events",
)


@pytest.fixture
def guarded(tmp_path: Path) -> Iterator[TestClient]:
    settings = Settings(
        database_url=f"sqlite:///{tmp_path / 'softevo.db'}",
        api_token="s3cret",
        protect_reads=True,
        poll_seconds=0.05,
    )
    with TestClient(create_app(settings, lambda _s: SerialEvaluator())) as client:
        yield client


def test_reads_need_the_token(guarded: TestClient) -> None:
    for path in READS:
        refused = guarded.get(path)
        assert refused.status_code == 401, path
        assert refused.headers["www-authenticate"] == "Bearer"
        assert "SOFTEVO_PROTECT_READS" in refused.json()["detail"]
        wrong = guarded.get(path, headers={"Authorization": "Bearer nope"})
        assert wrong.status_code == 403, path
    for path in ("/healthz", "/", "/static/api.js", "/openapi.json", "/docs"):
        assert guarded.get(path).status_code == 200, path
    assert guarded.get("/runs", headers={"Authorization": "Bearer s3cret"}).status_code == 200


def test_the_cookie_opens_reads_not_writes(guarded: TestClient) -> None:
    guarded.cookies.set("softevo_token", "s3cret")
    assert guarded.get("/runs").json()["total"] == 0
    assert guarded.get("/runs/7").status_code == 404  # the route answers, not the guard
    refused = guarded.post("/runs", json={"preset": "quick", "population": 4, "generations": 1})
    assert refused.status_code == 401  # a write needs the header: no CSRF through the cookie


def test_reads_stay_open_by_default(tmp_path: Path) -> None:
    settings = Settings(database_url=f"sqlite:///{tmp_path / 'softevo.db'}", api_token="s3cret")
    with TestClient(create_app(settings, lambda _s: SerialEvaluator())) as client:
        assert client.get("/runs").status_code == 200


def test_the_switch_needs_a_token_and_a_yes_or_no() -> None:
    assert Settings.from_env({"SOFTEVO_PROTECT_READS": "1", "SOFTEVO_API_TOKEN": "t"}).protect_reads
    assert not Settings.from_env({}).protect_reads
    with pytest.raises(ValueError, match="SOFTEVO_PROTECT_READS=1 needs SOFTEVO_API_TOKEN"):
        Settings.from_env({"SOFTEVO_PROTECT_READS": "1"})
    with pytest.raises(ValueError, match="SOFTEVO_PROTECT_READS: expected 1 or 0"):
        Settings.from_env({"SOFTEVO_PROTECT_READS": "maybe", "SOFTEVO_API_TOKEN": "t"})


def test_the_python_client_sends_the_token_on_reads(
    guarded: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    def through_app(base_url: str, headers: dict[str, str], timeout: float) -> httpx.Client:
        return TestClient(guarded.app, base_url=base_url, headers=headers)

    monkeypatch.setattr(client_module.httpx, "Client", through_app)
    with client_module.Client("http://testserver", token="s3cret") as client:
        assert client.get("/runs")["total"] == 0


DASHBOARD_CHECK = """
const input = { value: "", classList: { add() {}, remove() {} }, addEventListener() {},
                focus() {} };
const cookies = [];
globalThis.window = {};
globalThis.document = { getElementById: () => input, set cookie(text) { cookies.push(text); } };
globalThis.localStorage = { getItem: () => "s3 cret", setItem() {} };
const seen = [];
globalThis.fetch = async (path, options) => {
  seen.push(options.headers.Authorization || null);
  return { ok: true, status: 200, headers: { get: () => "application/json" },
           json: async () => ({}) };
};
const { api } = await import(process.argv[2]);
await api("/runs/1/curve");
console.log(JSON.stringify({ seen, cookies }));
"""


def test_the_dashboard_sends_the_token_on_reads_and_keeps_it_in_a_cookie(tmp_path: Path) -> None:
    node = shutil.which("node")
    if node is None:
        pytest.skip("no node to run the dashboard's JavaScript")
    module = tmp_path / "api.mjs"
    module.write_text((STATIC / "api.js").read_text())
    script = tmp_path / "check.mjs"
    script.write_text(DASHBOARD_CHECK)
    done = subprocess.run(
        [node, str(script), str(module)], capture_output=True, text=True, timeout=30, check=True
    )
    result = json.loads(done.stdout)
    assert result["seen"] == ["Bearer s3 cret"]
    assert result["cookies"][0].startswith("softevo_token=s3%20cret; path=/; SameSite=Strict")
