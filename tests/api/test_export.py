"""`?format=vxa|glb|stl` on a run's best robot and on any individual: through the real app, the
bytes equal what softevo.core.outputs.export writes for the robot file the JSON answer gives, with
the format's media type and a download name; a bad format or a robot the format cannot hold is a
422 that says why."""

from __future__ import annotations

import io
import xml.etree.ElementTree as ET
from typing import get_args

import pytest
import trimesh
from fastapi.testclient import TestClient

from softevo.api.export import ExportFormat
from softevo.core.outputs.export import FORMATS, MEDIA_TYPES, export_robot
from softevo.core.robots.robot_file import parse_robot
from tests.api.test_api import start, wait_for


def test_the_api_offers_the_cores_formats() -> None:
    assert get_args(ExportFormat) == FORMATS
    assert MEDIA_TYPES == {"vxa": "application/xml", "glb": "model/gltf-binary", "stl": "model/stl"}


@pytest.fixture
def finished(client: TestClient) -> int:
    run_id = start(client)
    wait_for(client, run_id, ("completed",))
    return run_id


def test_best_and_individual_as_files(client: TestClient, finished: int) -> None:
    best = parse_robot(client.get(f"/runs/{finished}/best").json())
    for format in FORMATS:
        response = client.get(f"/runs/{finished}/best", params={"format": format})
        assert response.status_code == 200, response.text
        assert response.headers["content-type"] == MEDIA_TYPES[format]
        assert response.headers["content-disposition"] == (
            f'attachment; filename="run-{finished}-best.{format}"'
        )
        assert response.content == export_robot(best, format)
    vxa = ET.fromstring(client.get(f"/runs/{finished}/best", params={"format": "vxa"}).content)
    structure = vxa.find("./VXC/Structure")
    assert [int(structure.findtext(f"{axis}_Voxels")) for axis in "XYZ"] == list(best.shape)

    detail = client.get(f"/runs/{finished}/individuals/7").json()
    robot = parse_robot(detail["robot"])
    response = client.get(f"/runs/{finished}/individuals/7", params={"format": "stl"})
    assert response.status_code == 200 and response.headers["content-type"] == "model/stl"
    disposition = response.headers["content-disposition"]
    assert disposition == f'attachment; filename="run-{finished}-individual-7.stl"'
    assert response.content == export_robot(robot, "stl")
    mesh = trimesh.load(io.BytesIO(response.content), file_type="stl")
    filled = sum(label != "empty" for label in robot.voxels)
    assert 0 < mesh.volume <= filled * robot.sim.edge_length**3 + 1e-9  # the kept voxels
    glb = client.get(f"/runs/{finished}/individuals/7", params={"format": "glb"})
    assert glb.content[:4] == b"glTF" and glb.headers["content-type"] == "model/gltf-binary"


def test_unknown_format_is_a_422_naming_the_formats(client: TestClient, finished: int) -> None:
    for url in (f"/runs/{finished}/best", f"/runs/{finished}/individuals/0"):
        response = client.get(url, params={"format": "obj"})
        assert response.status_code == 422
        [problem] = response.json()["detail"]
        assert problem["loc"] == ["query", "format"]
        assert all(f"'{format}'" in problem["msg"] for format in FORMATS), problem["msg"]
    assert client.get("/runs/999/best", params={"format": "stl"}).status_code == 404


def test_vxa_of_a_spring_encoded_robot_is_a_422_saying_why(client: TestClient) -> None:
    run_id = start(client, encoding="spring", shape=[2, 2, 2])
    wait_for(client, run_id, ("completed",))
    response = client.get(f"/runs/{run_id}/best", params={"format": "vxa"})
    assert response.status_code == 422
    [problem] = response.json()["detail"]
    assert problem["loc"] == ["query", "format"] and "vxa needs" in problem["msg"]
    stl = client.get(f"/runs/{run_id}/best", params={"format": "stl"})
    assert stl.status_code == 200 and stl.content == export_robot(
        parse_robot(client.get(f"/runs/{run_id}/best").json()), "stl"
    )


def test_openapi_lists_the_format_and_the_file_types(client: TestClient) -> None:
    paths = client.get("/openapi.json").json()["paths"]
    for path in ("/runs/{run_id}/best", "/runs/{run_id}/individuals/{number}"):
        operation = paths[path]["get"]
        [parameter] = [p for p in operation["parameters"] if p["name"] == "format"]
        assert parameter["in"] == "query"
        assert parameter["schema"]["anyOf"][0]["enum"] == list(FORMATS)
        content = operation["responses"]["200"]["content"]
        assert set(content) == {"application/json", *MEDIA_TYPES.values()}
