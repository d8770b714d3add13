"""`GET /runs/{id}/individuals` answers every evaluated individual's record of measures beside its
fitness, those of the in-process run to the bit, and the OpenAPI schema shows the object."""

from __future__ import annotations

import json

from fastapi.testclient import TestClient

from softevo.core.config import resolve
from softevo.core.nulls import to_null_record
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.evolution import Evolution
from tests.api.finished import finished

REQUEST = {
    "preset": "quick",
    "seed": 2,
    "population": 6,
    "generations": 2,
    "shape": [2, 2, 2],
    "objective": "forward",
    "sim": {"duration": 1.0},
}


def test_every_evaluated_individual_has_the_measures_of_the_run_in_process(
    client: TestClient,
) -> None:
    response = client.post("/runs", json=REQUEST)
    assert response.status_code == 201, response.text
    run = finished(client, response.json()["id"])
    assert run["status"] == "completed", run
    items = client.get(f"/runs/{run['id']}/individuals").json()["items"]
    evolution = Evolution.start(resolve(REQUEST))
    evolution.run(SerialEvaluator())
    assert len(items) == 12 and all(item["status"] != "pending" for item in items)
    for item in items:
        record = item["measures"]
        assert record == to_null_record(evolution.measures[item["genome_hash"]])
        assert record["forward_speed"] == item["fitness"]  # the objective's measure
        assert record["energy"] is None and record["stable"] == 1.0
    one = client.get(f"/runs/{run['id']}/individuals/{items[0]['id']}").json()
    assert one["measures"] == items[0]["measures"]
    schema = json.dumps(client.get("/openapi.json").json()["components"]["schemas"])
    assert "what the simulation measured, by name" in schema
