"""MAP-Elites' variation options through the service (issue 38): shown by GET /algorithms,
refused with a 422 that names the option."""

from __future__ import annotations

from fastapi.testclient import TestClient

RUN = {"preset": "quick", "algorithm": "map-elites", "population": 4, "generations": 1}


def test_map_elites_options_are_listed_and_bad_ones_refused_by_name(client: TestClient) -> None:
    listed = {entry["name"]: entry for entry in client.get("/algorithms").json()}
    fields = listed["map-elites"]["options"]["properties"]
    bad_rate = {"variation": "mutation", "label_rate": 2.0}
    refused = client.post("/runs", json={**RUN, "options": bad_rate})
    misplaced = client.post("/runs", json={**RUN, "options": {"real": "iso-line"}})
    assert {"variation", "label_rate", "real", "sigma", "line_sigma"} <= set(fields)
    assert refused.status_code == 422 and "options.label_rate" in refused.text
    assert misplaced.status_code == 422
    assert "options.real: applies to variation 'mutation' only" in misplaced.text
