"""Tasks through the service: terrain and objective on a run, task presets, sweeps over tasks."""

from __future__ import annotations

import pytest
from fastapi.testclient import TestClient

from softevo.core.physics import simulate
from softevo.core.robots.robot_file import parse_robot
from softevo.core.robots.tasks import TASKS
from tests.api.finished import finished

TINY = {
    "population": 4,
    "generations": 2,
    "shape": [2, 2, 2],
    "sim": {"duration": 1.0, "settle_time": 0.3},
}


def test_a_run_on_a_slope_is_scored_by_its_objective(client: TestClient) -> None:
    """The stored best fitness is the best robot's climb rate on the slope, re-simulated."""
    body = {
        **TINY,
        "preset": "quick",
        "seed": 2,
        "objective": "climb",
        "sim": {"duration": 1.0, "terrain": {"kind": "slope", "angle_deg": 8}},
    }
    response = client.post("/runs", json=body)
    assert response.status_code == 201, response.text
    run = finished(client, response.json()["id"])
    assert run["status"] == "completed"
    assert run["config"]["objective"] == "climb"
    assert run["config"]["sim"]["terrain"] == {"kind": "slope", "angle_deg": 8.0}
    best = client.get(f"/runs/{run['id']}/best").json()
    assert best["sim"]["terrain"]["kind"] == "slope"
    result, _ = simulate(parse_robot(best))
    assert result.climb_rate == run["progress"]["best_fitness"]
    assert result.speed != run["progress"]["best_fitness"]  # not the default objective
    replay = client.get(f"/runs/{run['id']}/best/replay").json()
    assert replay["terrain"]["kind"] == "slope" and len(replay["terrain"]["mesh"]["x"]) > 10
    assert replay["measures"]["climb_rate"] == result.climb_rate


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"sim": {"terrain": {"kind": "stairs"}}}, "terrain"),
        ({"sim": {"terrain": {"kind": "steps", "height": 0.2, "depth": 0.0}}}, "depth"),
        ({"objective": "fastest"}, "objective"),
    ],
)
def test_a_bad_terrain_or_objective_is_refused_naming_it(
    client: TestClient, change: dict, field: str
) -> None:
    response = client.post("/runs", json={"preset": "quick", **change})
    assert response.status_code == 422
    assert field in str(response.json()["detail"])
    assert client.get("/runs").json()["total"] == 0


def test_presets_list_every_task_with_what_it_asks(client: TestClient) -> None:
    presets = {p["name"]: p for p in client.get("/presets").json()}
    for name, (asks, terrain, objective) in TASKS.items():
        assert asks in presets[name]["description"]
        assert presets[name]["settings"]["sim"]["terrain"] == terrain
        assert presets[name]["settings"]["objective"] == objective


def test_a_sweep_over_tasks_and_seeds(client: TestClient) -> None:
    body = {**TINY, "tasks": ["task-flat", "task-stairs"], "seeds": [1, 2]}
    body["shapes"] = [TINY["shape"]]
    del body["shape"]
    response = client.post("/sweeps", json=body)
    assert response.status_code == 201, response.text
    groups = response.json()["boxes"]
    assert [(g["task"], g["shape"]) for g in groups] == [
        ("task-flat", [2, 2, 2]),
        ("task-stairs", [2, 2, 2]),
    ]
    for group in groups:
        runs = [finished(client, run_id) for run_id in group["run_ids"]]
        assert sorted(run["seed"] for run in runs) == [1, 2]
        assert {run["preset"] for run in runs} == {group["task"]}
        assert {run["config"]["objective"] for run in runs} == {TASKS[group["task"]][2]}
        assert all(run["status"] == "completed" for run in runs)


def test_a_sweep_gives_tasks_or_a_preset_not_both(client: TestClient) -> None:
    response = client.post("/sweeps", json={"preset": "quick", "tasks": ["task-flat"]})
    assert response.status_code == 422
    assert "tasks or a preset" in response.text
    response = client.post("/sweeps", json={"tasks": ["task-moon"]})
    assert response.status_code == 422
