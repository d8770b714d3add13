"""The dashboard in a real headless Chromium (Debian's, driven by playwright) against a live
`softevo serve` with a finished run and a running one. Screenshots go to test-artifacts/."""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from tests.api.dashboard.live import serve, wait

pytestmark = [pytest.mark.browser, pytest.mark.slow]
ARTIFACTS = Path(__file__).resolve().parents[3] / "test-artifacts"
SMALL = {
    "preset": "quick",
    "seed": 2,
    "population": 8,
    "generations": 4,
    "sim": {"duration": 1.5, "settle_time": 0.3},
}
#: dt = 3 ms in the paper profile is past the stability limit of the ground contact for most
#: robots: failed ones (no speed) in every generation, some simulated there and some reused from
#: the cache
FAILING = {
    **SMALL,
    "seed": 4,
    "generations": 3,
    "sim": {**SMALL["sim"], "profile": "paper", "dt": 0.003},
}
LONG = {
    "preset": "quick",
    "seed": 3,
    "population": 8,
    "generations": 3000,  # runs past the module however fast the service is: cancelled at the end
    "sim": {"duration": 3.0, "settle_time": 0.3},
}


def chromium() -> str:
    for name in ("chromium", "chromium-browser"):
        if path := shutil.which(name):
            return path
    if os.environ.get("CI") == "true":
        pytest.fail("Debian's chromium is needed under CI and is not installed")
    pytest.skip("chromium is not installed (apt-get install chromium)")


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[httpx.Client]:
    with serve(tmp_path_factory.mktemp("dashboard")) as client:
        yield client


@pytest.fixture(scope="module")
def runs(server: httpx.Client) -> Iterator[dict[str, int]]:
    """A finished run, one with failed robots, and a running one (cancelled at the end)."""
    done = server.post("/runs", json=SMALL).json()["id"]
    failing = server.post("/runs", json=FAILING).json()["id"]
    runs = (done, failing)
    wait(
        lambda: all(server.get(f"/runs/{i}").json()["status"] == "completed" for i in runs),
        60,
        "runs done",
    )
    running = server.post("/runs", json=LONG).json()["id"]
    wait(
        lambda: server.get(f"/runs/{running}").json()["progress"]["generation"] >= 1,
        60,
        "running run has a generation",
    )
    yield {"done": done, "failing": failing, "running": running}
    server.post(f"/runs/{running}/cancel")


@pytest.fixture(scope="module")
def page(server: httpx.Client) -> Iterator[Any]:
    executable = chromium()
    try:
        import playwright.sync_api as playwright_api
    except ImportError:
        if os.environ.get("CI") == "true":
            pytest.fail("playwright is needed under CI and is not installed (the dev extra)")
        pytest.skip("playwright is not installed (pip install -e .[dev])")
    base = str(server.base_url).rstrip("/")
    outside: list[str] = []

    def only_local(route: Any) -> None:
        """Let through this machine's servers only; remember and abort anything else."""
        url = route.request.url
        if url.startswith(("http://127.0.0.1:", "data:")):
            route.continue_()
        else:
            outside.append(url)
            route.abort()

    with playwright_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(
            executable_path=executable,
            args=["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader"],
        )
        page = browser.new_page(viewport={"width": 1400, "height": 1100})
        errors: list[str] = []
        page.on("pageerror", lambda error: errors.append(str(error)))
        page.route("**/*", only_local)
        page.base = base  # type: ignore[attr-defined]
        yield page
        browser.close()
    assert outside == [], f"the dashboard tried to reach outside the server: {outside}"
    assert errors == [], f"errors in the page: {errors}"


def shot(page: Any, name: str) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / f"{name}.png"), full_page=True)


def individuals_total(server: httpx.Client, run_id: int) -> int:
    return int(server.get(f"/runs/{run_id}/individuals", params={"limit": 1}).json()["total"])


def test_a_finished_run_its_charts_and_the_replay(
    page: Any, server: httpx.Client, runs: dict[str, int]
) -> None:
    run_id = runs["done"]
    page.goto(f"{page.base}/#/runs/{run_id}")
    page.wait_for_function(
        "window.softevo.replay && window.softevo.replay.frames > 0", timeout=30000
    )
    curve = server.get(f"/runs/{run_id}/curve").json()["generations"]
    assert page.evaluate("window.softevo.charts.curve.data[0].length") == len(curve) == 4
    shown = page.evaluate("window.softevo.charts.curve.data[1]")  # best so far
    assert shown == [row["best_so_far"] for row in curve]
    assert page.evaluate("window.softevo.dots") == individuals_total(server, run_id) == 32
    assert page.evaluate("window.softevo.charts.diversity.data[0].length") == len(curve)
    # the replay plays: its frame advances and the WebGL canvas shows something else
    assert page.evaluate("window.softevo.replay.renderer") == "webgl"
    canvas = "document.querySelector('#replay-canvas canvas').toDataURL()"
    first = (page.evaluate("window.softevo.replay.frame"), page.evaluate(canvas))
    # wait for another frame, not for a fixed time: a fixed wait can be a whole loop of the
    # 1.5 s replay on a busy machine and land on the same frame again
    page.wait_for_function(
        f"window.softevo.replay.frame !== {first[0]}", timeout=10000
    )  # the replay's frame advances
    second = (page.evaluate("window.softevo.replay.frame"), page.evaluate(canvas))
    assert second[1] != first[1], "the canvas did not change while playing"
    # shaded voxels by default (as many faces as the replay has), the springs as an option
    replayed = server.get(f"/runs/{run_id}/best/replay", params={"fps": 30}).json()
    assert page.evaluate("window.softevo.replay.voxels") == len(replayed["faces"]) > 0
    assert page.evaluate("window.softevo.replay.springs") is False
    page.click("#replay-springs")
    assert page.evaluate("window.softevo.replay.springs") is True
    page.click("#replay-springs")
    shot(page, "dashboard-run")
    # pause stops it; the slider moves it; the speed control sets the pace
    page.click("#replay-play")
    paused = page.evaluate("window.softevo.replay.frame")
    page.wait_for_timeout(400)
    assert page.evaluate("window.softevo.replay.frame") == paused
    target = (paused + page.evaluate("window.softevo.replay.frames") // 2) % page.evaluate(
        "window.softevo.replay.frames"
    )
    page.eval_on_selector(
        "#replay-slider",
        f"(s) => {{ s.value = {target}; s.dispatchEvent(new Event('input')); }}",
    )
    page.wait_for_function(f"window.softevo.replay.frame === {target}", timeout=5000)
    assert page.text_content("#replay-clock") == f"{replayed['times'][target]:.2f} s"
    page.select_option("#replay-speed", "4")
    assert page.evaluate("window.softevo.replay.speed") == 4
    page.click("#replay-play")
    page.wait_for_function(f"window.softevo.replay.frame !== {target}", timeout=5000)
    # a click on a dot replays that individual
    point = page.evaluate("""() => {
        const u = window.softevo.charts.population;
        u.over.scrollIntoView({block: "center"});
        const r = u.over.getBoundingClientRect();
        const i = u.data[1].findLastIndex(v => v !== null);
        return [r.left + u.valToPos(u.data[0][i], 'x'), r.top + u.valToPos(u.data[1][i], 'y')];
    }""")
    page.mouse.click(*point)
    page.wait_for_function("window.softevo.replay.label.startsWith('individual')", timeout=15000)
    shot(page, "dashboard-replay")


def test_failed_robots_are_marked_whether_simulated_or_reused(
    page: Any, server: httpx.Client, runs: dict[str, int]
) -> None:
    run_id = runs["failing"]
    items = server.get(f"/runs/{run_id}/individuals", params={"limit": 5000}).json()["items"]
    failed = [i for i in items if i["fitness"] is None]
    assert {"failed", "cached"} <= {i["status"] for i in failed}, "the run has no reused failure"
    page.goto(f"{page.base}/#/runs/{run_id}")
    page.wait_for_function(
        f"document.querySelector('h2').textContent.startsWith('Run #{run_id}') && "
        "window.softevo.replay && window.softevo.replay.label.startsWith('the fastest')",
        timeout=30000,
    )
    assert page.evaluate("window.softevo.dots") == len(items)
    assert page.evaluate("window.softevo.failedDots") == len(failed)
    marks = page.evaluate("window.softevo.charts.population.data[2].filter(v => v === 0).length")
    assert marks == len(failed)
    shot(page, "dashboard-failed")


def test_a_running_run_updates_live(page: Any, server: httpx.Client, runs: dict[str, int]) -> None:
    run_id = runs["running"]
    page.goto(f"{page.base}/#/runs/{run_id}")
    page.wait_for_function("window.softevo.charts.curve !== undefined", timeout=30000)
    before = page.evaluate("window.softevo.charts.curve.data[0].length")
    page.wait_for_function(
        f"window.softevo.charts.curve.data[0].length >= {before + 2}", timeout=30000
    )
    shown = page.evaluate("window.softevo.charts.curve.data[0].length")
    committed = server.get(f"/runs/{run_id}").json()["progress"]["generation"]
    assert before + 2 <= shown <= committed
    assert page.evaluate("window.softevo.dots") >= shown * LONG["population"]
    shot(page, "dashboard-live")
    # every committed generation is drawn once the page catches up, one point each
    page.wait_for_function(
        f"window.softevo.charts.curve.data[0].length >= {committed}", timeout=30000
    )
    drawn = page.evaluate("window.softevo.charts.curve.data[0]")
    assert drawn == list(range(len(drawn)))
    # the run's own Cancel button stops it
    page.click("#summary button:has-text('Cancel')")
    wait(lambda: server.get(f"/runs/{run_id}").json()["status"] == "cancelled", 30, "cancelled")
    page.wait_for_function(
        "document.getElementById('summary').textContent.includes('cancelled')", timeout=15000
    )


def test_a_run_started_from_the_page_appears(
    page: Any, server: httpx.Client, runs: dict[str, int]
) -> None:
    page.goto(f"{page.base}/#/")
    page.wait_for_selector(f"tr[data-run='{runs['done']}']")
    shot(page, "dashboard-runs")
    page.select_option("#start-form select[name=preset]", "quick")
    page.fill("#start-form input[name=population]", "4")
    page.fill("#start-form input[name=generations]", "2")
    page.fill("#start-form input[name=seed]", "77")
    page.click("#start-form button[type=submit]")
    page.wait_for_function(
        "document.getElementById('start-message').textContent.includes('queued')", timeout=15000
    )
    new_id = int(page.text_content("#start-message").split()[1])
    page.wait_for_selector(f"tr[data-run='{new_id}']", timeout=15000)
    run = server.get(f"/runs/{new_id}").json()
    assert run["seed"] == 77 and run["config"]["population"] == 4
    # a refused request shows the server's reason
    page.fill("#start-form input[name=shape]", "99x99x99")
    page.click("#start-form button[type=submit]")
    page.wait_for_function(
        "document.getElementById('start-message').textContent.includes('422')", timeout=15000
    )


def test_a_sweep(page: Any, server: httpx.Client) -> None:
    body = {**SMALL, "shapes": [[2, 2, 2], [3, 2, 2]], "seeds": [1, 2]}
    body.pop("seed")
    sweep = server.post("/sweeps", json=body).json()
    ids = [i for b in sweep["boxes"] for i in b["run_ids"]]
    wait(
        lambda: all(server.get(f"/runs/{i}").json()["status"] == "completed" for i in ids),
        120,
        "sweep done",
    )
    page.goto(f"{page.base}/#/sweeps/{sweep['id']}")
    page.wait_for_function("Object.keys(window.softevo.charts).length === 3", timeout=30000)
    means = page.evaluate("window.softevo.charts.boxes.data[1]")
    api = server.get(f"/sweeps/{sweep['id']}").json()
    assert means == [b["best_mean"] for b in api["boxes"]]
    shot(page, "dashboard-sweep")


def test_static_files_are_local_and_typed(server: httpx.Client) -> None:
    html = server.get("/")
    assert html.status_code == 200 and html.headers["content-type"].startswith("text/html")
    assert "http://" not in html.text and "https://" not in html.text
    for path, kind in (
        ("/static/app.js", "javascript"),
        ("/static/style.css", "text/css"),
        ("/static/vendor/three/three.module.js", "javascript"),
        ("/static/vendor/uplot/uPlot.iife.min.js", "javascript"),
    ):
        response = server.get(path)
        assert response.status_code == 200 and kind in response.headers["content-type"], path
    assert "/" not in server.get("/openapi.json").json()["paths"]


def test_the_api_docs_render_offline(page: Any, server: httpx.Client) -> None:
    """/docs is Swagger UI from the package: it draws every endpoint with nothing fetched from
    outside (the page fixture aborts and reports any request off this machine)."""
    page.goto(f"{page.base}/docs")
    page.wait_for_selector(".swagger-ui .opblock", timeout=30000)
    assert "softevo" in page.inner_text(".swagger-ui .info .title")
    shown = set(
        page.eval_on_selector_all(".opblock-summary-path", "ps => ps.map(p => p.dataset.path)")
    )
    assert set(server.get("/openapi.json").json()["paths"]) <= shown
    shot(page, "api-docs")


def test_the_token_is_asked_for_and_kept(page: Any, tmp_path: Path) -> None:
    """With SOFTEVO_API_TOKEN set, a start without it is refused and the token field is pointed
    at; once typed, the token is kept in localStorage and the run starts."""
    with serve(tmp_path, token="s3cret") as guarded:
        base = str(guarded.base_url).rstrip("/")
        page.goto(f"{base}/#/")
        page.evaluate("localStorage.removeItem('softevo-token')")
        page.reload()
        page.wait_for_selector("#start-form")
        page.fill("#start-form input[name=population]", "4")
        page.fill("#start-form input[name=generations]", "1")
        page.click("#start-form button[type=submit]")
        page.wait_for_function(
            "document.getElementById('start-message').textContent.startsWith('401')",
            timeout=15000,
        )
        assert "wanted" in (page.get_attribute("#token", "class") or "")
        page.fill("#token", "s3cret")
        page.dispatch_event("#token", "change")
        assert page.evaluate("localStorage.getItem('softevo-token')") == "s3cret"
        page.click("#start-form button[type=submit]")
        page.wait_for_function(
            "document.getElementById('start-message').textContent.includes('queued')",
            timeout=15000,
        )
        assert guarded.get("/runs").json()["total"] == 1
        page.reload()  # the token survives a reload
        page.wait_for_selector("#start-form")
        assert page.input_value("#token") == "s3cret"


def test_a_map_elites_run_shows_its_archive_and_replays_a_picked_elite(
    page: Any, server: httpx.Client
) -> None:
    body = {
        **SMALL,
        "algorithm": "map-elites",
        "descriptors": ["voxels", "actuated"],
        "bins": [6, 5],
        "generations": 5,
    }
    run_id = server.post("/runs", json=body).json()["id"]
    wait(lambda: server.get(f"/runs/{run_id}").json()["status"] == "completed", 60, "QD run")
    page.goto(f"{page.base}/#/runs/{run_id}")
    page.wait_for_function(
        "window.softevo.archive && window.softevo.replay && window.softevo.replay.frames > 0",
        timeout=30000,
    )
    archive = server.get(f"/runs/{run_id}/archive").json()
    assert page.evaluate("window.softevo.archive.cells.length") == len(archive["cells"]) > 1
    curve = server.get(f"/runs/{run_id}/curve").json()["generations"]
    assert page.evaluate("window.softevo.charts.coverage.data[1]") == [r["coverage"] for r in curve]
    assert page.evaluate("window.softevo.charts.qd_score.data[1]") == [r["qd_score"] for r in curve]
    # a filled cell drawn where the archive says: a click on its centre replays that elite
    elite = max(archive["cells"], key=lambda c: c["fitness"])
    point = page.evaluate(
        """([i, j]) => {
        const canvas = document.querySelector('canvas.archive');
        canvas.scrollIntoView({block: "center"});
        const r = canvas.getBoundingClientRect(), s = r.width / canvas.width;
        const left = 48, top = 8, w = (canvas.width - 56) / 6, hgt = (canvas.height - 48) / 5;
        return [r.left + (left + (i + 0.5) * w) * s, r.top + (top + (4 - j + 0.5) * hgt) * s];
    }""",
        elite["cell"],
    )
    page.mouse.click(*point)
    page.wait_for_function(
        f"window.softevo.replay.label.startsWith('elite of cell {elite['cell'][0]}, "
        f"{elite['cell'][1]}')",
        timeout=15000,
    )
    shot(page, "dashboard-archive")


def open_finished_replay(page: Any, server: httpx.Client, body: dict[str, Any]) -> int:
    """Start `body` as a run, wait until it completes, open its page until the replay is drawn."""
    run_id = server.post("/runs", json=body).json()["id"]
    wait(lambda: server.get(f"/runs/{run_id}").json()["status"] == "completed", 60, "the run")
    page.goto(f"{page.base}/#/runs/{run_id}")
    page.wait_for_function(
        "window.softevo.replay && window.softevo.replay.frames > 0 && window.softevo.replay.drawn",
        timeout=30000,
    )
    return run_id


def test_a_run_on_stairs_replays_over_the_terrain(page: Any, server: httpx.Client) -> None:
    open_finished_replay(
        page, server, {**SMALL, "preset": "task-stairs", "shape": [3, 3, 3], "generations": 2}
    )
    assert page.evaluate("window.softevo.replay.terrain") == "steps"
    assert "steps" in page.text_content("#task") and "forward" in page.text_content("#task")
    assert "terrain: steps" in page.text_content("#replay-measures")
    page.eval_on_selector("#replay", "(p) => p.scrollIntoView({block: 'center'})")
    shot(page, "dashboard-terrain")


def test_a_co_designed_robot_is_coloured_by_phase(page: Any, server: httpx.Client) -> None:
    open_finished_replay(page, server, {**SMALL, "encoding": "voxel-phase", "generations": 2})
    assert page.evaluate("window.softevo.replay.phaseColours") == "hue"
    assert "coloured by phase" in page.text_content("#replay")
    shot(page, "dashboard-voxel-phase")
