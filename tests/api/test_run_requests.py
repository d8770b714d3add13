"""Run bodies a user gets wrong, through the service: counts that are not integers, terrain out
of what a simulation can meet, a terrain at the top of the body, several problems at once; and
the terrain kinds' defaults (issue 39)."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient

from tests.api.finished import finished

QUICK: dict[str, Any] = {"preset": "quick", "population": 4, "generations": 1}


def _refused(client: TestClient, body: dict[str, Any]) -> list[dict[str, Any]]:
    response = client.post("/runs", json={**QUICK, **body})
    assert response.status_code == 422, response.text
    assert client.get("/runs").json()["total"] == 0
    return response.json()["detail"]


@pytest.mark.parametrize("bins", [[True], [4.0]])
def test_bins_are_integers(client: TestClient, bins: list[Any]) -> None:
    body = {"algorithm": "map-elites", "descriptors": ["voxels"], "bins": bins}
    detail = _refused(client, body)
    assert detail[0]["loc"][:2] == ["body", "bins"], detail


@pytest.mark.parametrize(
    ("terrain", "field"),
    [
        ({"kind": "steps", "height": 0.2, "depth": 1e-9}, "depth"),
        ({"kind": "hurdles", "height": 0.1, "spacing": 1e-6, "width": 1e-7}, "spacing"),
        ({"kind": "hurdles", "spacing": 1.0, "width": 1.0}, "width"),
        ({"kind": "rough", "amplitude": 0.1, "wavelength": 1e-300}, "wavelength"),
    ],
)
def test_terrain_below_what_a_simulation_meets_is_refused_naming_the_field(
    client: TestClient, terrain: dict[str, Any], field: str
) -> None:
    detail = _refused(client, {"sim": {"terrain": terrain}})
    assert all("float" not in problem["loc"] for problem in detail), detail  # no spurious one
    assert field in str(detail[0]["loc"]) or f"{field}:" in detail[0]["msg"], detail


def test_every_terrain_problem_is_listed(client: TestClient) -> None:
    detail = _refused(client, {"sim": {"terrain": {"kind": "steps", "height": -1, "depth": 0}}})
    named = {problem["loc"][-1] for problem in detail}
    assert named == {"height", "depth"}, detail


def test_a_terrain_at_the_top_points_to_sim_terrain(client: TestClient) -> None:
    detail = _refused(client, {"terrain": {"kind": "slope", "angle_deg": 5}})
    assert detail[0]["loc"] == ["body", "terrain"]
    assert '{"sim": {"terrain"' in detail[0]["msg"], detail


@pytest.mark.parametrize("kind", ["rough", "steps", "hurdles"])
def test_a_terrain_kind_alone_takes_its_defaults(client: TestClient, kind: str) -> None:
    response = client.post("/runs", json={**QUICK, "sim": {"terrain": {"kind": kind}}})
    assert response.status_code == 201, response.text
    terrain = response.json()["config"]["sim"]["terrain"]
    assert terrain["kind"] == kind and len(terrain) > 2, terrain


def test_the_curve_as_csv_ends_its_lines_as_the_cli_does(client: TestClient) -> None:
    body = {**QUICK, "shape": [2, 2, 2], "sim": {"duration": 0.5, "settle_time": 0.1}}
    run = finished(client, client.post("/runs", json=body).json()["id"])
    text = client.get(f"/runs/{run['id']}/curve?format=csv").content
    assert text.count(b"\n") == 2 and b"\r" not in text  # header and one generation, LF


def test_a_budget_in_simulations_ends_the_run_and_is_shown_back(client: TestClient) -> None:
    """`max_simulations` (issue 51): the run stops at the first generation reaching it, well
    before its generations, and `GET /runs/{id}` says both; a bad value is one line."""
    body = {
        **QUICK,
        "shape": [2, 2, 2],
        "population": 4,
        "generations": 50,
        "max_simulations": 10,
        "sim": {"duration": 0.5, "settle_time": 0.1},
    }
    run = finished(client, client.post("/runs", json=body).json()["id"])
    assert run["status"] == "completed", run
    assert run["config"]["max_simulations"] == run["progress"]["max_simulations"] == 10
    assert 10 <= run["progress"]["evaluations"] < 14 and run["progress"]["generation"] < 50
    rows = len(client.get(f"/runs/{run['id']}/curve").json()["generations"])
    after = client.get(f"/runs/{run['id']}/individuals", params={"generation": rows}).json()
    assert after["total"] == 0, after  # the next row's births, bred, are not kept by the end
    response = client.post("/runs", json={**QUICK, "max_simulations": 0})
    assert response.status_code == 422, response.text
    detail = response.json()["detail"]
    assert detail[0]["loc"] == ["body", "max_simulations"] and len(detail) == 1, detail
