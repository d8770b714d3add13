"""The runs list shows a small picture of each finished run's best robot (issue 19): the <img>
is lazy, its PNG loads (naturalWidth > 0, the server's thumbnail size) and the screenshot is
the one docs/dashboard.md shows (test-artifacts/dashboard-thumbnails.png)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import httpx
import pytest

from softevo.core.outputs.picture import THUMBNAIL_SIZE
from tests.api.dashboard.live import wait
from tests.api.dashboard.test_browser import SMALL, page, server, shot  # noqa: F401 (fixtures)

pytestmark = [pytest.mark.browser, pytest.mark.slow]


@pytest.fixture(scope="module")
def finished(server: httpx.Client) -> Iterator[list[int]]:  # noqa: F811
    ids = [server.post("/runs", json={**SMALL, "seed": seed}).json()["id"] for seed in (5, 6)]
    wait(
        lambda: all(server.get(f"/runs/{i}").json()["status"] == "completed" for i in ids),
        90,
        "runs done",
    )
    yield ids


def test_finished_runs_show_their_best_robot(page: Any, finished: list[int]) -> None:  # noqa: F811
    page.goto(f"{page.base}/#/")
    for run_id in finished:
        selector = f"tr[data-run='{run_id}'] img.thumbnail"
        page.wait_for_selector(selector)
        assert page.get_attribute(selector, "loading") == "lazy"
        page.wait_for_function(
            f'(() => {{ const i = document.querySelector("{selector}"); '
            "return i && i.complete && i.naturalWidth > 0; })()",
            timeout=15000,
        )
        size = page.evaluate(
            f'(() => {{ const i = document.querySelector("{selector}"); '
            "return [i.naturalWidth, i.naturalHeight]; })()"
        )
        assert tuple(size) == THUMBNAIL_SIZE
    shot(page, "dashboard-thumbnails")
