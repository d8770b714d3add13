"""The dashboard's Pareto front (issue 36): a run with objectives shows the scatter of its
front, the same points as `GET /runs/{id}/front`, and a click on a point replays that robot.
Issue 48: the front is drawn over every robot evaluated, the page names the objectives, the
hypervolume is charted over the simulations run, and the runs list says the algorithm. Issue
51: beside it, the normalised hypervolume (0-1), with each objective's reference and ideal."""

from __future__ import annotations

from typing import Any

import httpx
import pytest

from tests.api.dashboard.live import wait
from tests.api.dashboard.test_browser import SMALL, page, server, shot  # noqa: F401 (fixtures)

pytestmark = [pytest.mark.browser, pytest.mark.slow]


def test_an_nsga2_run_shows_its_front_and_replays_a_picked_point(
    page: Any,  # noqa: F811
    server: httpx.Client,  # noqa: F811
) -> None:
    body = {**SMALL, "algorithm": "nsga2", "objectives": ["speed", "-cost_of_transport"]}
    run_id = server.post("/runs", json=body).json()["id"]
    wait(lambda: server.get(f"/runs/{run_id}").json()["status"] == "completed", 60, "the run")
    held: list[Any] = []  # the best robot's replay, held back until a point was picked
    page.route("**/best/replay*", lambda route: held.append(route))
    page.goto(f"{page.base}/#/runs/{run_id}")
    page.wait_for_function("window.softevo.front && window.softevo.replay", timeout=30000)
    front = server.get(f"/runs/{run_id}/front").json()
    assert page.evaluate("window.softevo.front.points.length") == len(front["points"]) >= 1
    # every robot drawn: the axes scale to them all, so a point moves until the last is in
    drawn = len(measured(listed(server, run_id)))
    page.wait_for_function(f"window.softevo.frontDots === {drawn}", timeout=60000)
    target = front["points"][-1]
    point = page.evaluate(
        """(id) => {
        const canvas = document.querySelector('canvas.front');
        canvas.scrollIntoView({block: "center"});
        const r = canvas.getBoundingClientRect(), s = r.width / canvas.width;
        return [r.left + window.softevo.frontDrawn[id][0] * s,
                r.top + window.softevo.frontDrawn[id][1] * s];
    }""",
        target["id"],
    )
    page.mouse.click(*point)
    page.wait_for_function(
        f"window.softevo.replay.label.startsWith('front robot of generation "
        f"{target['generation']}, index {target['index']}')",
        timeout=60000,
    )
    picked = page.evaluate("window.softevo.replay.label")
    for _ in range(600):  # asked for when the page was opened, so here long since
        if held:
            break
        page.wait_for_timeout(50)
    assert held, "the page never asked for the best robot's replay"
    held[0].continue_()  # the best robot comes after the pick: the pick stays on screen
    page.wait_for_function("window.softevo.replaysDropped === 1", timeout=60000)
    assert page.evaluate("window.softevo.replay.label") == picked
    shot(page, "dashboard-front")
    readable(page, server, run_id)


def listed(service: httpx.Client, run_id: int) -> list[dict]:
    """The run's individuals, as the page lists them (a test run holds fewer than 1000)."""
    return service.get(f"/runs/{run_id}/individuals", params={"limit": 1000}).json()["items"]


def measured(individuals: list[dict]) -> list[dict]:
    """The robots the scatter draws: every one evaluated, survivors (drawn already) left out."""
    return [i for i in individuals if i["fitness"] is not None and i["operator"] != "survivor"]


def readable(browser: Any, service: httpx.Client, run_id: int) -> None:
    """What issue 48 asked of the page of an nsga2 run and of the runs list."""
    task = browser.text_content("#task")
    assert "objectives: speed (m/s), higher is better" in task and "fitness =" not in task
    assert "cost of transport (dimensionless), lower is better" in task
    assert "nsga2" in browser.text_content("h2")
    everyone = listed(service, run_id)
    assert browser.evaluate("window.softevo.frontDots") == len(measured(everyone))
    curve = service.get(f"/runs/{run_id}/curve").json()["generations"]
    spent = [sum(r["evaluations"] for r in curve[: g + 1]) for g in range(len(curve))]
    assert browser.evaluate("window.softevo.charts.hypervolume.data[0]") == spent
    volumes = browser.evaluate("window.softevo.charts.hypervolume.data[1]")
    assert volumes == [r["hypervolume"] for r in curve]
    scaled = browser.evaluate("window.softevo.charts.hypervolume.data[2]")  # issue 51
    assert scaled == [r["normalised_hypervolume"] for r in curve] and 0 < scaled[-1] <= 1
    title = browser.text_content("#hypervolume h3")
    assert "normalised (0-1, each objective scaled from reference to ideal: speed 0 to 1" in title
    series = "[...document.querySelectorAll('#hypervolume .u-series')].map(s => s.textContent)"
    assert browser.evaluate(series)[-1] == f"normalised (0-1){scaled[-1]:.3f}"
    legend = "[...document.querySelectorAll('#population .u-series')].map(s => s.textContent)"
    assert browser.evaluate(legend)[-1] == f"failed0 of {len(everyone)}"  # a value, not clipped
    browser.goto(f"{browser.base}/#/")
    row = f"tr[data-run='{run_id}']"
    browser.wait_for_selector(row)
    assert browser.text_content(f"{row} td.algorithm") == "nsga2"
    assert browser.text_content(f"{row} td.encoding") == "voxel"
    assert browser.text_content(f"{row} td.objectives") == "speed ↑, cost of transport ↓"
    assert browser.text_content(f"{row} td.task") == "flat / speed"
    headers = browser.eval_on_selector_all("#runs th", "cells => cells.map(c => c.textContent)")
    assert {"algorithm", "encoding", "objectives", "task"} <= set(headers)
