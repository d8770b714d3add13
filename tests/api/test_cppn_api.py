"""A `cppn` run through the service: its individuals carry the network genome, their robot
files the decoded body; boxes up to 10x10x10 pass the service's limits, bad configs are 422."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient

from softevo.api.settings import Limits
from softevo.api.validation import RequestError, run_config
from tests.api.finished import finished

REQUEST = {
    "preset": "quick",
    "encoding": "cppn",
    "seed": 2,
    "population": 4,
    "generations": 2,
    "shape": [2, 2, 2],
    "sim": {"duration": 0.5, "settle_time": 0.1},
}


def test_a_cppn_run_stores_networks_and_serves_decoded_bodies(client: TestClient) -> None:
    response = client.post("/runs", json=REQUEST)
    assert response.status_code == 201, response.text
    run = finished(client, response.json()["id"])
    assert run["status"] == "completed", run
    items = client.get(f"/runs/{run['id']}/individuals").json()["items"]
    one = client.get(f"/runs/{run['id']}/individuals/{items[0]['id']}").json()
    assert one["genome"]["encoding"] == "cppn" and one["genome"]["discrete"][0] >= 5
    robot = one["robot"]
    assert robot["format"] == "softevo.robot/1" and len(robot["voxels"]) == 8
    assert client.get(f"/runs/{run['id']}/best").json()["format"] == "softevo.robot/1"


def test_big_cppn_boxes_pass_the_limits_and_bad_configs_do_not() -> None:
    limits = Limits()
    config = run_config({"preset": "cppn-8x8x8", "shape": [10, 10, 10]}, limits)
    assert config.encoding == "cppn" and config.shape == (10, 10, 10)
    with pytest.raises(RequestError, match="shape"):
        run_config({"preset": "cppn-8x8x8", "shape": [11, 10, 10]}, limits)


@pytest.mark.parametrize(
    ("body", "field"),
    [
        ({"encoding": "cppn2"}, "encoding"),
        ({"encoding": "cppn", "descriptors": ["bogus"]}, "descriptors"),
        ({"encoding": "cppn", "shape": [11, 10, 10]}, "shape"),
    ],
)
def test_bad_cppn_configs_are_422(client: TestClient, body: dict, field: str) -> None:
    response = client.post("/runs", json={"preset": "quick", **body})
    assert response.status_code == 422, response.text
    assert field in response.text
