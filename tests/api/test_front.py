"""`GET /runs/{id}/front` (issue 36): the points are mutually non-dominated and every other
evaluated individual is dominated by, or equal to, one of them; `objectives` refused in one
line naming the field; the curve carries the normalised hypervolume (issue 51), and a run
stored before it existed is still served."""

from __future__ import annotations

import numpy as np
from fastapi.testclient import TestClient
from sqlalchemy import update

from softevo import library
from softevo.api.cost import cost_factor
from softevo.api.models import GenerationRow, RunRow
from softevo.core.config import resolve
from softevo.core.search import pareto
from softevo.core.search.front import front_values
from softevo.core.search.vectors import ideal_point, reference_point
from tests.api.test_api import wait_for

RUN = {
    "preset": "quick",
    "seed": 2,
    "shape": [2, 2, 2],
    "population": 6,
    "generations": 3,
    "sim": {"duration": 1.0},
    "algorithm": "nsga2",
    "objectives": ["speed", "-cost_of_transport"],
}


def test_the_front_dominates_every_other_individual(client: TestClient) -> None:
    run_id = client.post("/runs", json=RUN).json()["id"]
    wait_for(client, run_id, ("completed",))
    front = client.get(f"/runs/{run_id}/front").json()
    assert front["objectives"][1] == {
        "measure": "cost_of_transport",
        "goal": "min",
        "reference": 100_000.0,
        "ideal": 0.0,
    }
    specs = resolve(RUN).objectives
    points = front_values(specs, front["points"])
    assert len(points) >= 1 and not np.isnan(points).any()
    for point in points:
        assert not any(pareto.dominates(other, point) for other in points)
    listed = client.get(f"/runs/{run_id}/individuals", params={"limit": 1000}).json()["items"]
    everyone = front_values(specs, [i for i in listed if i["fitness"] is not None])
    for point in everyone[~np.isnan(everyone).any(axis=1)]:
        assert any(pareto.dominates(f, point) or (f == point).all() for f in points)
    curve = client.get(f"/runs/{run_id}/curve").json()["generations"]
    assert curve == library.evolve(RUN, workers=1).curve  # the service's run is the library's
    assert curve[-1]["hypervolume"] > 0 and curve[-1]["front_size"] >= 1
    scaled = pareto.normalised_hypervolume(points, ideal_point(specs), reference_point(specs))
    assert curve[-1]["normalised_hypervolume"] == scaled and 0 < scaled <= 1
    csv = client.get(f"/runs/{run_id}/curve", params={"format": "csv"}).text
    assert csv.splitlines()[0].endswith(",hypervolume,front_size,normalised_hypervolume")
    robots = client.get(f"/runs/{run_id}/front", params={"robots": True}).json()["points"]
    assert all(point["robot"]["format"] == "softevo.robot/1" for point in robots)
    assert all(point["measures"]["cost_of_transport"] is not None for point in robots)


def test_a_run_without_objectives_has_no_front_and_bad_ones_are_named(
    client: TestClient,
) -> None:
    plain = client.post("/runs", json={**RUN, "objectives": [], "generations": 1}).json()["id"]
    assert client.get(f"/runs/{plain}/front").status_code == 404
    # the runs list carries what the dashboard's columns show (issue 48): algorithm, encoding,
    # objectives and task, in each run's resolved config
    listed = {run["id"]: run["config"] for run in client.get("/runs").json()["items"]}
    assert listed[plain]["algorithm"] == "nsga2" and listed[plain]["encoding"] == "voxel"
    assert not listed[plain].get("objectives") and listed[plain]["objective"] == "speed"
    assert listed[plain]["sim"]["terrain"]["kind"] == "flat"
    response = client.post("/runs", json={**RUN, "objectives": ["speed", "sped"]})
    assert response.status_code == 422
    assert "objectives: item 1: unknown measure 'sped'" in response.text


def test_a_run_stored_before_the_normalised_hypervolume_is_served(client: TestClient) -> None:
    run_id = client.post("/runs", json={**RUN, "generations": 1}).json()["id"]
    wait_for(client, run_id, ("completed",))
    stored = client.get(f"/runs/{run_id}").json()["config"]
    without = [{k: v for k, v in item.items() if k != "ideal"} for item in stored["objectives"]]
    with client.app.state.db.engine.begin() as connection:  # type: ignore[attr-defined]
        connection.execute(
            update(RunRow)
            .where(RunRow.id == run_id)
            .values(config={**stored, "objectives": without})
        )
        connection.execute(
            update(GenerationRow)
            .where(GenerationRow.run_id == run_id)
            .values(normalised_hypervolume=None)
        )
    (row,) = client.get(f"/runs/{run_id}/curve").json()["generations"]
    assert "normalised_hypervolume" not in row and row["hypervolume"] > 0
    csv = client.get(f"/runs/{run_id}/curve", params={"format": "csv"}).text
    assert csv.splitlines()[1].endswith(",")  # the column, empty
    front = client.get(f"/runs/{run_id}/front").json()
    assert [item["ideal"] for item in front["objectives"]] == [1.0, 0.0]  # the defaults


def test_objectives_that_read_the_actuators_work_are_budgeted_as_efficiency() -> None:
    plain, energy = resolve({}), resolve({"objectives": ["speed", "-cost_of_transport"]})
    assert cost_factor(energy) == cost_factor(resolve({"objective": "efficiency"})) > 1.0
    assert cost_factor(resolve({"objectives": ["speed", "distance"]})) == cost_factor(plain)


def test_openapi_names_the_normalised_hypervolume_and_the_ideal(client: TestClient) -> None:
    schemas = client.get("/openapi.json").json()["components"]["schemas"]
    column = schemas["CurveRow"]["properties"]["normalised_hypervolume"]
    assert "from its reference (0) to its ideal (1)" in column["description"]
    assert "ideal" in schemas["ObjectiveIn"]["properties"]
