"""`softevo run --descriptors heading,voxels`: the behavioural descriptor in the archive's files,
its heat map's axis labelled with its unit, and in --help."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from softevo.core.config import resolve
from softevo.core.outputs.archive_figures import archive_figure
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.evolution import Evolution
from tests.softevo.inprocess import softevo


def test_a_heading_run_writes_its_archive_with_the_heading_axis(tmp_path: Path) -> None:
    out = tmp_path / "heading"
    done = softevo(
        "run",
        "--preset",
        "quick",
        "--algorithm",
        "map-elites",
        "--descriptors",
        "heading,voxels",
        "--bins",
        "8,4",
        "--generations",
        "3",
        "--population",
        "8",
        "--duration",
        "1",
        "--seed",
        "2",
        "--workers",
        "1",
        "--out",
        str(out),
    )
    assert done.returncode == 0, done.stderr
    archive = json.loads((out / "archive.json").read_text())
    expected = Evolution.start(
        resolve(
            {
                "preset": "quick",
                "algorithm": "map-elites",
                "descriptors": ["heading", "voxels"],
                "bins": [8, 4],
                "generations": 3,
                "population": 8,
                "seed": 2,
                "sim": {"duration": 1.0},
            }
        )
    )
    expected.run(SerialEvaluator())
    assert archive == expected.state.archive.to_json() and archive["elites"]
    with (out / "archive.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [float(r["heading"]) for r in rows] == [e["values"][0] for e in archive["elites"]]
    assert all(-180 <= float(r["heading"]) <= 180 for r in rows)
    assert (out / "archive.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    figure = archive_figure(archive, "heading", "speed (m/s)")
    axes = figure.axes[0]
    assert axes.get_xlabel().startswith("heading: ") and "degrees" in axes.get_xlabel()
    assert axes.get_xlim() == (-180.0, 180.0)
    assert axes.get_ylabel().startswith("voxels: ")


def test_help_and_a_bad_name_list_the_catalogue_with_heading(tmp_path: Path) -> None:
    shown = softevo("run", "--help")
    assert "heading [-180, 180]" in " ".join(shown.stdout.split())
    done = softevo(
        "run",
        "--algorithm",
        "map-elites",
        "--descriptors",
        "drift",
        "--bins",
        "4",
        "--out",
        str(tmp_path),
    )
    assert done.returncode != 0
    assert "known: voxels, actuated, soft, height, heading" in done.stderr
