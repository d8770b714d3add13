"""`softevo reproduce --qd --quick`: MAP-Elites and voxel-phase against the GA, through the API."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from softevo.cli import main


def test_the_qd_suite_compares_the_three_variants_on_the_gas_budget(tmp_path: Path) -> None:
    assert main(["reproduce", "--qd", "--quick", "--out", str(tmp_path)]) == 0
    with (tmp_path / "qd.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [(r["box"], r["variant"]) for r in rows] == [
        ("2x2x2", "ga"),
        ("2x2x2", "map-elites"),
        ("2x2x2", "voxel-phase"),
    ]
    ga, elites, _ = rows
    assert 0 < float(elites["simulations_mean"]) <= float(ga["simulations_mean"])  # its budget
    for row in rows:
        assert 0 < float(row["coverage_mean"]) <= 1 and float(row["best_mean"]) > 0
        assert float(row["near_best_cells_mean"]) <= float(row["coverage_mean"]) * 64
    assert "MAP-Elites" in (tmp_path / "qd.md").read_text()
    for name in ("qd.png", "qd_archives.png"):
        assert (tmp_path / name).read_bytes()[:4] == b"\x89PNG"


def test_two_suites_at_once_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["reproduce", "--tasks", "--qd", "--out", str(tmp_path)])
    assert exited.value.code == 2 and "one at a time" in capsys.readouterr().err
