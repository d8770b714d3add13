"""`softevo reproduce --steady --quick`: steady-state against the GA on the GA's simulations,
and a size-timed evaluator that changes nothing, through the API, end to end."""

from __future__ import annotations

import csv
from pathlib import Path

from softevo.cli import main
from softevo.reproduce.steady import overtaken


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as handle:
        return list(csv.DictReader(handle))


def test_steady_state_is_read_on_the_gas_simulations_and_timing_changes_nothing(
    tmp_path: Path,
) -> None:
    assert main(["reproduce", "--steady", "--quick", "--workers", "1", "--out", str(tmp_path)]) == 0
    rows = {r["method"]: r for r in _rows(tmp_path / "steady.csv")}
    assert list(rows) == ["GA", "steady-state", "steady-state, the GA's births"]
    ga, matched, long = rows.values()
    assert 0 < float(matched["simulations_mean"]) <= float(ga["simulations_mean"])
    assert long["births_by_seed"] == ga["births_by_seed"] == "24"
    assert float(long["simulations_mean"]) >= float(matched["simulations_mean"])
    assert all(float(r["wall_mean"]) > 0 and float(r["best_mean"]) > 0 for r in rows.values())
    timing = _rows(tmp_path / "timing.csv")[0]
    assert timing["curve_equal"] == timing["state_equal"] == timing["service_equal"] == "True"
    assert int(timing["batches"]) >= 1 and float(timing["held_seconds"]) > 0
    assert all(float(r["wall_ratio"]) > 0 for r in rows.values())
    text = (tmp_path / "steady.md").read_text()
    assert "in 1 of 1 runs" in text and "first curve in 1 of 1 runs" in text
    assert (tmp_path / "steady.png").read_bytes()[:4] == b"\x89PNG"


def test_overtaken_counts_batches_that_land_after_later_births() -> None:
    assert overtaken([0, 4, 8]) == 0
    assert overtaken([4, 0, 8, 6, 12]) == 2
