"""GET /sweeps (newest first, paged like GET /runs) and bounding boxes given as the CLI's text."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient

from softevo.cli import main

BASE = {"preset": "quick", "population": 4, "generations": 1, "seeds": [1]}


def cli_error(capsys: pytest.CaptureFixture[str], shape: str) -> str:
    """What `softevo run --shape SHAPE` says, after its "softevo run: error: "."""
    with pytest.raises(SystemExit):
        main(["run", "--preset", "quick", "--shape", shape])
    return capsys.readouterr().err.strip().splitlines()[-1].split("error: ", 1)[1]


def test_sweeps_are_listed_newest_first_and_paged(client: TestClient) -> None:
    assert client.get("/sweeps").json() == {"items": [], "total": 0, "offset": 0, "limit": 50}
    made = [client.post("/sweeps", json={**BASE, "shapes": [[2, 2, n]]}).json() for n in (1, 2, 3)]

    def newest_two() -> tuple[dict, dict]:
        """The first page of two, and the newest sweep read on its own."""
        page = client.get("/sweeps", params={"limit": 2}).json()
        return page, client.get(f"/sweeps/{made[2]['id']}").json()

    page, newest = newest_two()
    for _ in range(20):  # its run may start or finish between the two reads: read them again
        if page["items"][0] == newest:
            break
        page, newest = newest_two()
    assert page["total"] == 3 and page["limit"] == 2
    assert [s["id"] for s in page["items"]] == [made[2]["id"], made[1]["id"]]
    assert page["items"][0]["boxes"][0]["shape"] == [2, 2, 3]
    assert page["items"][0] == newest  # the list shows each sweep as GET /sweeps/{id} does
    rest = client.get("/sweeps", params={"offset": 2}).json()
    assert [s["id"] for s in rest["items"]] == [made[0]["id"]]
    assert client.get("/sweeps", params={"limit": 0}).status_code == 422
    assert "get" in client.get("/openapi.json").json()["paths"]["/sweeps"]
    for sweep in made:
        for run_id in sweep["boxes"][0]["run_ids"]:
            client.post(f"/runs/{run_id}/cancel")


def test_a_box_given_as_text_is_taken_as_the_cli_takes_it(client: TestClient) -> None:
    run = client.post("/runs", json={"preset": "quick", "generations": 1, "shape": "2X2x3"})
    assert run.status_code == 201, run.text
    assert run.json()["config"]["shape"] == [2, 2, 3]
    sweep = client.post("/sweeps", json={**BASE, "shapes": ["2x2x1", [2, 2, 2]]})
    assert sweep.status_code == 201, sweep.text
    assert [b["shape"] for b in sweep.json()["boxes"]] == [[2, 2, 1], [2, 2, 2]]
    for run_id in [run.json()["id"], *(i for b in sweep.json()["boxes"] for i in b["run_ids"])]:
        client.post(f"/runs/{run_id}/cancel")


@pytest.mark.parametrize("shape", ["4x4", "4xa", "0x4x4", "32x32x32"])
def test_a_bad_box_as_text_is_refused_in_the_cli_words(
    client: TestClient, capsys: pytest.CaptureFixture[str], shape: str
) -> None:
    said = cli_error(capsys, shape)
    assert said.startswith("shape: ")
    response = client.post("/runs", json={"preset": "quick", "shape": shape})
    assert response.status_code == 422
    (error,) = response.json()["detail"]
    assert error["loc"] == ["body", "shape"]
    assert said.removeprefix("shape: ") in error["msg"]
    swept = client.post("/sweeps", json={**BASE, "shapes": ["2x2x2", shape]})
    assert swept.status_code == 422
    assert swept.json()["detail"][0]["loc"] == ["body", "shapes", 1]
    assert said.removeprefix("shape: ") in swept.json()["detail"][0]["msg"]
    assert client.get("/runs").json()["total"] == 0
