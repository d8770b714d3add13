"""MAP-Elites through the service: the archive endpoint, curve rows with coverage and QD-score,
the same archive as `softevo run`'s, and errors that name the field."""

from __future__ import annotations

from fastapi.testclient import TestClient

from softevo.core.config import resolve
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.robots.robot import LABELS
from softevo.core.robots.robot_file import parse_robot
from softevo.core.search.descriptors import describe
from softevo.core.search.evolution import Evolution
from tests.api.finished import finished

QD = {
    "preset": "quick",
    "seed": 4,
    "population": 8,
    "generations": 3,
    "shape": [2, 2, 2],
    "algorithm": "map-elites",
    "descriptors": ["voxels", "actuated"],
    "bins": [4, 3],
    "sim": {"duration": 1.0, "settle_time": 0.3},
}


def test_a_map_elites_run_serves_the_archive_softevo_run_builds(client: TestClient) -> None:
    response = client.post("/runs", json=QD)
    assert response.status_code == 201, response.text
    run = finished(client, response.json()["id"])
    assert run["status"] == "completed", run
    archive = client.get(f"/runs/{run['id']}/archive", params={"robots": True}).json()
    evolution = Evolution.start(resolve(QD))
    evolution.run(SerialEvaluator())
    expected = evolution.state.archive
    assert [c["cell"] for c in archive["cells"]] == [list(e.cell) for e in expected.ordered()]
    assert [c["fitness"] for c in archive["cells"]] == [e.fitness for e in expected.ordered()]
    assert archive["coverage"] == expected.coverage == len(archive["cells"]) / 12
    assert archive["qd_score"] == expected.qd_score
    assert [a["name"] for a in archive["descriptors"]] == ["voxels", "actuated"]
    assert archive["generations"] == 3
    for cell in archive["cells"]:  # each cell's elite is that individual, with its descriptors
        individual = client.get(f"/runs/{run['id']}/individuals/{cell['id']}").json()
        assert (individual["generation"], individual["index"]) == (
            cell["generation"],
            cell["index"],
        )
        assert individual["fitness"] == cell["fitness"]
        robot = parse_robot(cell["robot"])
        labels = [LABELS.index(label) for label in robot.voxels]
        assert list(describe(["voxels", "actuated"], labels, (2, 2, 2))) == cell["values"]
    curve = client.get(f"/runs/{run['id']}/curve").json()["generations"]
    assert [row["coverage"] for row in curve] == [r["coverage"] for r in evolution.curve()]
    assert curve[-1]["qd_score"] == archive["qd_score"]
    csv = client.get(f"/runs/{run['id']}/curve", params={"format": "csv"}).text
    assert csv.splitlines()[0].endswith(",coverage,qd_score")


def test_a_ga_run_has_no_archive_and_its_curve_rows_are_unchanged(client: TestClient) -> None:
    body = {**QD, "algorithm": "ga", "descriptors": [], "bins": []}
    run = finished(client, client.post("/runs", json=body).json()["id"])
    response = client.get(f"/runs/{run['id']}/archive")
    assert response.status_code == 404
    assert "without descriptors" in response.json()["detail"]
    row = client.get(f"/runs/{run['id']}/curve").json()["generations"][0]
    assert "coverage" not in row and "qd_score" not in row


def test_a_bad_archive_request_is_refused_naming_the_field(client: TestClient) -> None:
    for change, words in (
        ({"descriptors": ["voxels", "legs"]}, "unknown ['legs']"),
        ({"bins": [300, 300]}, "90000 cells"),
        ({"descriptors": []}, "map-elites needs at least one descriptor"),
    ):
        response = client.post("/runs", json={**QD, **change})
        assert response.status_code == 422, response.text
        assert words in response.text
