"""`softevo reproduce --objectives --quick`: NSGA-II, the weighted-sum GA and random search on one
budget, and AFPO against the GA, through the API, end to end."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from softevo.cli import main


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as handle:
        return list(csv.DictReader(handle))


def test_the_objectives_suite_reads_every_method_at_one_budget(tmp_path: Path) -> None:
    assert main(["reproduce", "--objectives", "--quick", "--out", str(tmp_path)]) == 0
    trade = _rows(tmp_path / "tradeoff.csv")
    assert [r["method"] for r in trade] == [
        "NSGA-II",
        "GA w=0.25",
        "GA w=0.5",
        "GA w=0.75",
        "random search",
    ]
    budget = max(float(r["simulations_mean"]) for r in trade if r["method"].startswith("GA"))
    for row in trade:  # at most the weighted GAs' simulations, a front, a volume
        assert 0 < float(row["simulations_mean"]) <= budget
        assert float(row["front_size_mean"]) >= 1 and float(row["hypervolume_mean"]) > 0
        assert float(row["hypervolume_default_mean"]) > float(row["hypervolume_mean"])
    age = _rows(tmp_path / "afpo.csv")
    assert [(r["box"], r["method"]) for r in age] == [("2x2x2", "GA"), ("2x2x2", "AFPO")]
    ga, afpo = age
    assert abs(float(afpo["simulations_mean"]) - float(ga["simulations_mean"])) <= 3
    assert all(0 < float(r["min_diversity_mean"]) <= float(r["final_diversity_mean"]) for r in age)
    assert "NSGA-II" in (tmp_path / "objectives.md").read_text()
    for name in ("fronts.png", "hypervolume.png", "afpo.png"):
        assert (tmp_path / name).read_bytes()[:4] == b"\x89PNG"


def test_the_suites_are_run_one_at_a_time(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["reproduce", "--qd", "--objectives", "--out", str(tmp_path)])
    assert exited.value.code == 2 and "--qd and --objectives" in capsys.readouterr().err
