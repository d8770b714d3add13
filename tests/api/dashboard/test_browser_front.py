"""The dashboard's Pareto front (issue 36): a run with objectives shows the scatter of its
front, the same points as `GET /runs/{id}/front`, and a click on a point replays that robot."""

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
    page.goto(f"{page.base}/#/runs/{run_id}")
    page.wait_for_function("window.softevo.front && window.softevo.replay", timeout=30000)
    front = server.get(f"/runs/{run_id}/front").json()
    assert page.evaluate("window.softevo.front.points.length") == len(front["points"]) >= 1
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
        timeout=15000,
    )
    shot(page, "dashboard-front")
