"""MAP-Elites over the behavioural `heading` through the service: the archive endpoint reports
each elite's measured heading like any descriptor value, the same as `softevo run`'s archive;
the axis and the OpenAPI schema name it; a bad name lists the catalogue."""

from __future__ import annotations

from fastapi.testclient import TestClient

from softevo.core.config import resolve
from softevo.core.physics import simulate
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.robots.robot_file import parse_robot
from softevo.core.search.evolution import Evolution
from tests.api.finished import finished

HEADING = {
    "preset": "quick",
    "seed": 4,
    "population": 8,
    "generations": 3,
    "shape": [2, 2, 2],
    "algorithm": "map-elites",
    "descriptors": ["heading", "actuated"],
    "bins": [6, 3],
    "sim": {"duration": 1.0, "settle_time": 0.3},
}


def test_the_archive_endpoint_reports_each_elites_measured_heading(client: TestClient) -> None:
    response = client.post("/runs", json=HEADING)
    assert response.status_code == 201, response.text
    run = finished(client, response.json()["id"])
    assert run["status"] == "completed", run
    archive = client.get(f"/runs/{run['id']}/archive", params={"robots": True}).json()
    evolution = Evolution.start(resolve(HEADING))
    evolution.run(SerialEvaluator())
    expected = evolution.state.archive.ordered()
    assert expected and [
        (c["cell"], c["values"], c["fitness"], c["generation"], c["index"])
        for c in archive["cells"]
    ] == [(list(e.cell), list(e.values), e.fitness, e.generation, e.index) for e in expected]
    axis = archive["descriptors"][0]
    assert (axis["name"], axis["low"], axis["high"], axis["bins"]) == ("heading", -180, 180, 6)
    assert "degrees" in axis["help"]
    cell = archive["cells"][0]  # the elite's robot, simulated again, heads the same way
    result, _ = simulate(parse_robot(cell["robot"]))
    assert cell["values"][0] == result.heading


def test_openapi_names_heading_and_a_bad_name_lists_the_catalogue(client: TestClient) -> None:
    schema = client.get("/openapi.json").text
    assert "heading, in degrees, measured by the simulation" in schema
    response = client.post("/runs", json={**HEADING, "descriptors": ["heading", "drift"]})
    assert response.status_code == 422, response.text
    assert "known: voxels, actuated, soft, height, heading" in response.text
