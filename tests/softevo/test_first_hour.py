"""What a newcomer meets first (issue 39): `quick` says that it scores under half an actuation
period, and `softevo replay` draws one whole period unless told otherwise."""

from __future__ import annotations

import json
import math
from pathlib import Path

from PIL import Image

from softevo.core.config import PRESET_DESCRIPTIONS, resolve
from softevo.core.outputs import picture
from softevo.core.robots.robot_file import load_robot
from tests.softevo.inprocess import softevo


def test_quick_says_it_scores_under_half_a_period() -> None:
    sim = resolve({"preset": "quick"}).sim
    assert sim.measured_time < math.pi / sim.omega  # what the description says
    assert "under half an actuation period" in PRESET_DESCRIPTIONS["quick"]


def test_a_replay_draws_one_actuation_period_by_default(examples: Path, tmp_path: Path) -> None:
    crawler = examples / "crawler_4x4x4.json"
    assert picture.one_period(load_robot(crawler)) == 2 * math.pi  # 1 rad/s: 6.28 s, not 3
    out = tmp_path / "period.gif"
    done = softevo("replay", str(crawler), "--out", str(out), "--fps", "1")
    assert done.returncode == 0, done.stderr
    with Image.open(out) as image:
        assert image.n_frames == round(2 * math.pi)


def test_a_quick_robot_replays_at_least_three_seconds(examples: Path, tmp_path: Path) -> None:
    fast = json.loads((examples / "crawler_4x4x4.json").read_text())
    fast["sim"] = {**fast["sim"], "omega": 10.0}  # a period of 0.63 s
    path = tmp_path / "fast.json"
    path.write_text(json.dumps(fast))
    assert picture.one_period(load_robot(path)) == picture.SECONDS


def test_map_elites_without_a_map_takes_the_presets(tmp_path: Path) -> None:
    config = resolve({"preset": "quick", "algorithm": "map-elites"})
    assert (config.descriptors, config.bins) == (("voxels", "actuated"), (8, 8))
    one = resolve({"preset": "quick", "algorithm": "map-elites", "descriptors": ["soft"]})
    assert one.bins == (8,)
    out = tmp_path / "qd"
    done = softevo(
        "run",
        "--preset",
        "quick",
        "--algorithm",
        "map-elites",
        "--population",
        "4",
        "--generations",
        "1",
        "--shape",
        "2x2x2",
        "--duration",
        "1",
        "--out",
        str(out),
    )
    assert done.returncode == 0, done.stderr
    archive = json.loads((out / "archive.json").read_text())
    assert archive["descriptors"] == ["voxels", "actuated"] and archive["bins"] == [8, 8]
    for name in ("curve.csv", "population.csv", "archive.csv"):  # LF, as the API's CSV
        text = (out / name).read_bytes()
        assert b"\n" in text and b"\r" not in text, name


def test_every_option_of_the_first_commands_says_what_it_does() -> None:
    from softevo.cli import build_parser

    commands = build_parser()._subparsers._group_actions[0].choices  # type: ignore[union-attr]
    silent = [
        f"{name} {action.option_strings or action.dest}"
        for name, parser in commands.items()
        if name in ("run", "simulate", "export", "replay", "reproduce")
        for action in parser._actions
        if not action.help
    ]
    assert silent == [], silent


def test_reproduce_names_its_out_folder_in_full(tmp_path: Path) -> None:
    """--out is relative to the current folder: its help says so and errors give the full path."""
    (tmp_path / "a_file").write_text("")
    done = softevo("reproduce", "--quick", "--out", "a_file/results", cwd=tmp_path)
    assert done.returncode == 2
    assert f"--out {tmp_path / 'a_file' / 'results'}: cannot write there" in done.stderr
    help_text = " ".join(softevo("reproduce", "--help").stdout.split())
    assert "relative to the current folder" in help_text


def test_the_readmes_example_folder_is_the_one_softevo_run_names() -> None:
    """README's `softevo run --preset quick --seed 1` prints the folder default_out gives (the
    hash covers the whole config, so a new setting changes it: update README and
    docs/dashboard.md with it)."""
    from softevo.run_command import default_out

    folder = default_out(resolve({"preset": "quick", "seed": 1}))
    root = Path(__file__).resolve().parents[2]
    assert f"results in {folder}/" in (root / "README.md").read_text()
    assert f"softevo plot {folder} " in (root / "docs" / "dashboard.md").read_text()


def test_the_guides_help_points_to_are_shown_by_softevo_docs() -> None:
    listed = softevo("docs")
    assert listed.returncode == 0 and "tasks" in listed.stdout and "physics" in listed.stdout
    shown = softevo("docs", "docs/tasks.md")
    assert shown.returncode == 0 and shown.stdout.startswith("# Tasks")
    missing = softevo("docs", "nothing")
    assert missing.returncode == 1 and "guides:" in missing.stderr
