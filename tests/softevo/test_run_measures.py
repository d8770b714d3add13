"""Every individual's record of measures in what `softevo run` and the library leave: a column
per measure in population.csv, the records in cache.json and in the library's result; and a
folder written by the release before records (cache.json with the `heading` channel alone,
population.csv of four columns) resumed to the uninterrupted curve and archive."""

from __future__ import annotations

import csv
import json
from pathlib import Path

from softevo import library, run_store
from softevo.core.config import resolve
from softevo.results import POPULATION_COLUMNS, read_results
from tests.softevo.inprocess import softevo

SMALL = {
    "preset": "quick",
    "population": 6,
    "generations": 3,
    "seed": 4,
    "shape": [2, 2, 2],
    "sim": {"duration": 1.0},
}
HEADING = {
    **SMALL,
    "algorithm": "map-elites",
    "descriptors": ["heading", "voxels"],
    "bins": [6, 3],
    "generations": 4,
}


def rows_of(out: Path) -> list[dict[str, str]]:
    with (out / "population.csv").open(newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def test_population_csv_and_cache_json_keep_every_measure(tmp_path: Path) -> None:
    out = tmp_path / "run"
    args = [f"--{k}={v}" for k, v in SMALL.items() if k not in ("shape", "sim")]
    done = softevo("run", *args, "--shape", "2x2x2", "--workers", "1", "--out", str(out))
    assert done.returncode == 0, done.stderr
    rows = rows_of(out)
    assert tuple(rows[0])[:4] == POPULATION_COLUMNS
    assert {"speed", "heading", "forward_speed", "stable", "energy"} <= set(rows[0])
    for row in rows:  # a speed run: the fitness is its speed measure; energy was not measured
        assert row["speed"] == row["fitness"] and row["energy"] == ""
    cache = json.loads((out / "cache.json").read_text())
    assert cache["measures"].keys() == cache["fitness"].keys()
    assert all(cache["measures"][key]["speed"] == value for key, value in cache["fitness"].items())
    _, _, individuals = read_results(out)
    assert individuals[0]["measures"]["speed"] == individuals[0]["fitness"]


def test_the_librarys_result_carries_the_records_and_the_bests() -> None:
    result = library.evolve(SMALL, workers=1)
    assert result.best_measures is not None
    assert result.best_measures["speed"] == result.best_fitness
    assert result.to_json()["best"]["measures"] == result.best_measures
    assert len(result.measures) == result.evaluations
    assert all(record["stable"] in (0.0, 1.0) for record in result.measures.values())


def test_a_folder_of_the_release_before_records_resumes_to_the_same_archive(
    tmp_path: Path,
) -> None:
    whole = library.evolve(HEADING, workers=1)
    half = run_store.new(tmp_path, resolve({**HEADING, "generations": 2}))
    run_store.drive(half, 1, 2, lambda step: None)
    run_store.Checkpoints(half).flush()
    half.close()
    (tmp_path / "run.db").unlink()  # what the release before wrote: headings alone, and four
    cache = json.loads((tmp_path / "cache.json").read_text())  # population columns
    cache["heading"] = {key: r["heading"] for key, r in cache["measures"].items()}
    del cache["measures"]
    (tmp_path / "cache.json").write_text(json.dumps(cache))
    old_rows = [{c: row[c] for c in POPULATION_COLUMNS} for row in rows_of(tmp_path)]
    with (tmp_path / "population.csv").open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, POPULATION_COLUMNS)
        writer.writeheader()
        writer.writerows(old_rows)

    resumed = run_store.resume(tmp_path, HEADING["generations"])
    imported = run_store.evolution(resumed)
    assert all(set(record) == {"heading"} for record in imported.measures.values())
    run_store.drive(resumed, 1, HEADING["generations"], lambda step: None)
    result = library.Result.of(run_store.Checkpoints(resumed).flush())
    assert result.curve == whole.curve
    assert result.archive == whole.archive
    rows = rows_of(tmp_path)  # the old file goes on in its own columns
    assert tuple(rows[0]) == POPULATION_COLUMNS and len(rows) == 6 * HEADING["generations"]
