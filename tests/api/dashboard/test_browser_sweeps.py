"""The dashboard as a new user found it (issue 19): the start form's default, errors in the CLI's
words, legends with the latest values, the wall time, the replay agreeing with the summary, and
sweeps listed, started and followed live from the page, their curves named by seed."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from datetime import datetime
from typing import Any

import httpx
import pytest

from tests.api.dashboard.live import wait
from tests.api.dashboard.test_browser import SMALL, page, server, shot  # noqa: F401 (fixtures)
from tests.api.test_sweep_list import cli_error

pytestmark = [pytest.mark.browser, pytest.mark.slow]
X = "\N{MULTIPLICATION SIGN}"  # the dashboard's boxes: 2x2x2 as 2, x, 2, x, 2


@pytest.fixture(scope="module")
def done(server: httpx.Client) -> Iterator[int]:  # noqa: F811
    run_id = server.post("/runs", json=SMALL).json()["id"]
    wait(lambda: server.get(f"/runs/{run_id}").json()["status"] == "completed", 60, "run done")
    yield run_id


def wall_time(started: str, finished: str) -> str:
    """The dashboard's words for the seconds between two of the API's timestamps."""
    zoned = [
        datetime.fromisoformat(t if t[-1] == "Z" or "+" in t else t + "+00:00")
        for t in (started, finished)
    ]
    exact = max(0.0, (zoned[1] - zoned[0]).total_seconds())
    if exact < 9.95:
        return f"{exact:.1f} s"
    s = round(exact)
    hours, minutes, seconds = s // 3600, s % 3600 // 60, s % 60
    if hours:
        return f"{hours} h {minutes:02d} min"
    return f"{minutes} min {seconds:02d} s" if minutes else f"{seconds} s"


def test_the_start_forms_default_to_the_quick_preset(page: Any) -> None:  # noqa: F811
    page.goto(f"{page.base}/#/")
    page.wait_for_selector("#sweep-form")
    assert page.input_value("#start-form select[name=preset]") == "quick"
    assert page.input_value("#sweep-form select[name=preset]") == "quick"


def shows(page: Any, selector: str, text: str) -> None:  # noqa: F811
    """Wait for the element to say `text` (a message of the case before may still be there)."""
    with contextlib.suppress(Exception):  # a timeout: the assertion below says what was shown
        page.wait_for_function(
            "([s, t]) => document.querySelector(s).textContent === t", arg=[selector, text]
        )
    assert page.text_content(selector) == text


@pytest.mark.parametrize("shape", ["4x4", "4xa", "0x4x4"])
def test_a_bad_box_is_refused_in_the_cli_words(
    page: Any,  # noqa: F811
    server: httpx.Client,  # noqa: F811
    capsys: pytest.CaptureFixture[str],
    shape: str,
) -> None:
    said = cli_error(capsys, shape)  # e.g. "shape: expected three sides [nx, ny, nz], got [4, 4]"
    page.goto(f"{page.base}/#/")
    page.wait_for_selector("#start-form")
    total = server.get("/runs").json()["total"]
    page.fill("#start-form input[name=shape]", shape)
    page.click("#start-form button[type=submit]")
    shows(page, "#start-message", f"422: {said}")
    # the sweep form's boxes are read the same way, the box named by its place in the list
    page.fill("#sweep-form input[name=shapes]", f"2x2x2 {shape}")
    page.click("#sweep-form button[type=submit]")
    shows(page, "#sweep-message", f"422: {said.replace('shape: ', 'shapes.1: ')}")
    assert server.get("/runs").json()["total"] == total
    if shape == "4x4":
        page.eval_on_selector("#start-message", "(m) => m.scrollIntoView({block: 'center'})")
        shot(page, "dashboard-shape-error")


def legend(page: Any, chart: str) -> list[str]:  # noqa: F811
    values = f"#{chart} .u-legend .u-value"
    return page.eval_on_selector_all(values, "vs => vs.map(v => v.textContent)")


def test_legends_show_the_latest_values_until_hovered(page: Any, done: int) -> None:  # noqa: F811
    page.goto(f"{page.base}/#/runs/{done}")
    page.wait_for_function(
        "window.softevo.replay && window.softevo.replay.frames > 0", timeout=30000
    )
    data = page.evaluate("window.softevo.charts.curve.data")
    last = [series[-1] for series in data]
    shown = legend(page, "curve")
    assert "--" not in shown, shown
    assert [float(v) for v in shown] == pytest.approx(last, rel=1e-3, abs=1e-3)
    assert "--" not in legend(page, "diversity")
    # hovering the first generation shows its values; leaving the chart, the latest again
    page.eval_on_selector("#curve", "(p) => p.scrollIntoView({block: 'center'})")
    box = page.locator("#curve .u-over").bounding_box()
    page.mouse.move(box["x"] + 2, box["y"] + box["height"] / 2)
    page.wait_for_function("window.softevo.charts.curve.cursor.idx === 0")
    assert float(legend(page, "curve")[0]) == pytest.approx(data[0][0])
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] - 60)  # off the chart
    page.wait_for_function("window.softevo.charts.curve.cursor.idx === null")
    assert [float(v) for v in legend(page, "curve")] == pytest.approx(last, rel=1e-3, abs=1e-3)
    shot(page, "dashboard-legend")


def test_a_finished_run_shows_its_wall_time(
    page: Any,  # noqa: F811
    server: httpx.Client,  # noqa: F811
    done: int,
) -> None:
    run = server.get(f"/runs/{done}").json()
    page.goto(f"{page.base}/#/runs/{done}")
    page.wait_for_selector("#wall-time")
    expected = wall_time(run["started_at"], run["finished_at"])
    # longer ones in minutes and hours, with or without a time zone on the timestamps
    said = page.evaluate("""async () => { const {duration} = await import('/static/api.js');
        return [duration('2026-01-01T00:00:00', '2026-01-01T00:02:05.4'),
                duration('2026-01-01T00:00:00+00:00', '2026-01-01T01:03:00Z'),
                duration(null, '2026-01-01T00:00:00')]; }""")
    assert said == ["2 min 05 s", "1 h 03 min", None]
    shown = page.text_content("#wall-time")
    assert shown.startswith(", wall time ")
    if expected.endswith(" s") and "." in expected:  # the browser's clock has milliseconds only
        assert float(shown.split()[-2]) == pytest.approx(float(expected.split()[0]), abs=0.11)
    else:
        assert shown == f", wall time {expected}"


LOOK = """() => [window.softevo.replay && window.softevo.replay.label,
    window.softevo.run.progress.best_generation, document.getElementById('summary').textContent]"""


def test_the_replay_and_the_summary_name_the_same_best(
    page: Any,  # noqa: F811
    server: httpx.Client,  # noqa: F811
) -> None:
    """While a run improves, the best generation the summary names is the replay's, or the
    replay says it is loading that one, whenever the page is looked at (each look one
    evaluate: the page does not change during it)."""
    body = {**SMALL, "seed": 11, "population": 8, "generations": 40}
    body["sim"] = {"duration": 3.0, "settle_time": 0.3}  # slow enough to be seen improving
    run_id = server.post("/runs", json=body).json()["id"]
    page.goto(f"{page.base}/#/runs/{run_id}")
    page.wait_for_function("window.softevo.charts.curve !== undefined", timeout=30000)
    looks: list[list[Any]] = []
    while server.get(f"/runs/{run_id}").json()["status"] != "completed" or len(looks) < 5:
        looks.append(page.evaluate(LOOK))
        page.wait_for_timeout(100)
        assert len(looks) < 1500, "the run did not finish"
    page.wait_for_function("window.softevo.replay.label.startsWith('the fastest robot (')")
    looks.append(page.evaluate(LOOK))
    seen = [(label, generation, text) for label, generation, text in looks if label]
    assert seen, "the replay never showed"
    for label, generation, text in seen:  # the same generation, or the replay says it is behind
        assert f"(generation {generation})" in text
        named = f"(generation {generation})" in label
        assert named or label.endswith(f"a better one, of generation {generation}, is loading)")
    assert len({generation for _, generation, _ in seen}) >= 2, "no new best was followed live"
    final = server.get(f"/runs/{run_id}").json()["progress"]["best_generation"]
    assert seen[-1][1] == final


def test_sweeps_are_listed_started_and_followed_live(
    page: Any,  # noqa: F811
    server: httpx.Client,  # noqa: F811
) -> None:
    page.goto(f"{page.base}/#/")
    page.wait_for_selector("#sweep-form")
    page.fill("#sweep-form input[name=shapes]", "2x2x2 3x2x2")
    page.fill("#sweep-form input[name=seeds]", "5 6")
    page.fill("#sweep-form input[name=population]", "4")
    page.fill("#sweep-form input[name=generations]", "6")
    page.click("#sweep-form button[type=submit]")
    page.wait_for_function("location.hash.startsWith('#/sweeps/')", timeout=15000)
    sweep_id = int(page.evaluate("location.hash").rsplit("/", 1)[1])
    sweep = server.get(f"/sweeps/{sweep_id}").json()
    assert [b["shape"] for b in sweep["boxes"]] == [[2, 2, 2], [3, 2, 2]]
    assert sweep["request"]["seeds"] == [5, 6] and sweep["request"]["preset"] == "quick"
    page.wait_for_function("window.softevo.charts.boxes !== undefined", timeout=30000)
    # followed live: the page reaches "completed" without a reload, its bars the API's means
    page.wait_for_function(
        "document.querySelector('h2 .status')?.textContent === 'completed' && "
        "window.softevo.sweep.following === false",
        timeout=120000,
    )
    assert page.evaluate("window.softevo.sweep.opened") in ("queued", "running")
    assert page.evaluate("window.softevo.sweep.updates") >= 1
    done = server.get(f"/sweeps/{sweep_id}").json()
    assert page.evaluate("window.softevo.charts.boxes.data[1]") == [
        b["best_mean"] for b in done["boxes"]
    ]
    # the curves are named by seed, in the chart's legend, under the box's title
    chart = f"box-2{X}2{X}2"
    names = page.evaluate(f"window.softevo.charts['{chart}'].series.slice(1).map(s => s.label)")
    seeds = [server.get(f"/runs/{i}").json()["seed"] for i in done["boxes"][0]["run_ids"]]
    assert names == [f"seed {s}" for s in seeds] == ["seed 5", "seed 6"]
    labels = page.eval_on_selector_all(
        f"[id='{chart}'] .u-legend .u-label", "ls => ls.map(l => l.textContent)"
    )
    assert labels[1:] == names
    assert page.text_content(f"[id='{chart}'] h3").startswith(f"2{X}2{X}2")
    curve = server.get(f"/runs/{done['boxes'][0]['run_ids'][1]}/curve").json()["generations"]
    drawn = page.evaluate(f"window.softevo.charts['{chart}'].data[2]")
    assert drawn == [row["best_so_far"] for row in curve]
    rows = page.eval_on_selector_all(
        "#sweep-boxes tr", "rs => rs.map(r => [...r.cells].map(c => c.textContent))"
    )
    ids = [b["run_ids"] for b in done["boxes"]]
    assert [row[:3] for row in rows[1:]] == [
        [f"2{X}2{X}2", f"#{ids[0][0]} (5)#{ids[0][1]} (6)", "2/2"],
        [f"3{X}2{X}2", f"#{ids[1][0]} (5)#{ids[1][1]} (6)", "2/2"],
    ]
    shot(page, "dashboard-sweep-live")
    # the list shows it with its boxes, seeds and runs completed
    page.goto(f"{page.base}/#/")
    row = f"#sweeps tr[data-sweep='{sweep_id}']"
    page.wait_for_selector(row)
    cells = page.eval_on_selector_all(f"{row} td", "ts => ts.map(t => t.textContent)")
    assert cells == [
        f"sweep {sweep_id}",
        "completed",
        f"2{X}2{X}2, 3{X}2{X}2",
        "5, 6",
        "4/4",
        "quick",
    ]
    page.eval_on_selector("#sweeps", "(t) => t.scrollIntoView({block: 'center'})")
    shot(page, "dashboard-sweeps")


def test_a_sweep_over_tasks_is_started_from_the_form(
    page: Any,  # noqa: F811
    server: httpx.Client,  # noqa: F811
) -> None:
    page.goto(f"{page.base}/#/")
    page.wait_for_selector("#sweep-form")
    page.select_option("#sweep-form select[name=over]", "tasks")
    # each task is a preset with its own box: neither is asked for
    assert not page.is_visible("#sweep-form select[name=preset]")
    assert not page.is_visible("#sweep-form input[name=shapes]")
    for task in page.eval_on_selector_all(
        "#sweep-form input[name=tasks]", "ts => ts.map(t => t.value)"
    ):
        if task not in ("task-flat", "task-slope"):
            page.uncheck(f"#sweep-form input[value={task}]")
    page.fill("#sweep-form input[name=seeds]", "3")
    page.fill("#sweep-form input[name=population]", "4")
    page.fill("#sweep-form input[name=generations]", "1")
    page.click("#sweep-form button[type=submit]")
    page.wait_for_function("location.hash.startsWith('#/sweeps/')", timeout=15000)
    sweep_id = int(page.evaluate("location.hash").rsplit("/", 1)[1])
    sweep = server.get(f"/sweeps/{sweep_id}").json()
    assert sweep["request"]["tasks"] == ["task-flat", "task-slope"]
    assert "preset" not in sweep["request"] and sweep["request"]["seeds"] == [3]
    page.wait_for_function(
        "document.querySelector('h2 .status')?.textContent === 'completed' && "
        "window.softevo.sweep && window.softevo.sweep.following === false",
        timeout=120000,
    )
    rows = page.eval_on_selector_all(
        "#sweep-boxes tr td:first-child", "ts => ts.map(t => t.textContent)"
    )
    assert [row.split()[0] for row in rows] == ["task-flat", "task-slope"]
    titles = page.eval_on_selector_all(".panel h3", "hs => hs.map(h => h.textContent)")
    assert any(t.startswith("task-slope") and t.endswith("best so far per seed") for t in titles)
    names = page.evaluate("Object.values(window.softevo.sweep.labels)")
    assert names == [["seed 3"], ["seed 3"]]
