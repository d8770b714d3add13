"""`softevo run --algorithm map-elites`: the archive's files, the same as the run's state."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from softevo.core.config import resolve
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.evolution import Evolution
from tests.softevo.inprocess import softevo


def test_a_map_elites_run_writes_its_archive_and_heat_map(tmp_path: Path) -> None:
    out = tmp_path / "qd"
    done = softevo(
        "run",
        "--preset",
        "quick",
        "--algorithm",
        "map-elites",
        "--descriptors",
        "voxels,soft",
        "--bins",
        "5,4",
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
        "--json",
    )
    assert done.returncode == 0, done.stderr
    archive = json.loads((out / "archive.json").read_text())
    expected = Evolution.start(
        resolve(
            {
                "preset": "quick",
                "algorithm": "map-elites",
                "descriptors": ["voxels", "soft"],
                "bins": [5, 4],
                "generations": 3,
                "population": 8,
                "seed": 2,
                "sim": {"duration": 1.0},
            }
        )
    )
    expected.run(SerialEvaluator())
    assert archive == expected.state.archive.to_json()
    with (out / "archive.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [list(map(int, r["cell"].split("-"))) for r in rows] == [
        e["cell"] for e in archive["elites"]
    ]
    assert [float(r["fitness"]) for r in rows] == [e["fitness"] for e in archive["elites"]]
    assert set(rows[0]) == {"cell", "voxels", "soft", "fitness", "generation", "index", "genome"}
    assert (out / "archive.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    curve = json.loads(done.stdout)["generations"]
    assert curve[-1]["coverage"] == len(rows) / 20


def test_bad_bins_are_a_usage_error_naming_them(tmp_path: Path) -> None:
    done = softevo(
        "run",
        "--algorithm",
        "map-elites",
        "--descriptors",
        "voxels",
        "--bins",
        "ten",
        "--out",
        str(tmp_path),
    )
    assert done.returncode == 2 and "--bins" in done.stderr and "ten" in done.stderr
    done = softevo("run", "--algorithm", "map-elites", "--bins", "4,4,4", "--out", str(tmp_path))
    assert (
        done.returncode == 2 and "bins: one count per descriptor" in done.stderr
    )  # the preset's 2
