"""`softevo run` keeps its run in the service's store (run.db in the folder) and writes the other
files from it, at most every SAVE_SECONDS and when the run stops: an interrupt, between
generations or halfway through one, loses nothing committed, keeps the fitness that landed, and
`--resume` goes on to the uninterrupted run's curve, counts and files. A folder written before
the store is imported on resume and goes on the same way."""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from softevo import library, run_store
from softevo.api.driver import RunDriver
from softevo.api.store import folders
from softevo.core.config import resolve
from softevo.core.search.generation import Step

CONFIG = {
    "preset": "quick",
    "population": 6,
    "generations": 4,
    "seed": 3,
    "shape": [2, 2, 2],
    "sim": {"duration": 1.0},
}
#: NSGA-II and AFPO with objectives: their kept values, births, lineages and the front so far
#: ride in the state, and must come back from the store as they were.
PARETO = {"objectives": ["speed", "-cost_of_transport"]}


def stop_after(generations: int) -> Callable[[Step], None]:
    """A report that presses Ctrl-C once `generations` are committed."""

    def report(step: Step) -> None:
        if step.stats.generation + 1 == generations:
            raise KeyboardInterrupt

    return report


def finish(out: Path, generations: int) -> library.Result:
    folder = run_store.resume(out, generations)
    run_store.drive(folder, 1, generations, lambda step: None)
    return library.Result.of(run_store.Checkpoints(folder).flush())


def same(result: library.Result, whole: library.Result) -> None:
    assert result.curve == whole.curve
    assert (result.evaluations, result.saved) == (whole.evaluations, whole.saved)
    assert result.state == whole.state and result.archive == whole.archive
    assert result.front == whole.front and result.measures == whole.measures


@pytest.mark.parametrize(
    "changes",
    [{}, {"algorithm": "nsga2", **PARETO}, {"algorithm": "afpo", **PARETO}],
    ids=["ga", "nsga2", "afpo"],
)
def test_an_interrupt_between_generations_resumes_to_the_uninterrupted_run(
    tmp_path: Path, changes: dict
) -> None:
    config = resolve({**CONFIG, **changes})
    whole = library.evolve(config, workers=1)
    folder = run_store.new(tmp_path, config)
    with pytest.raises(KeyboardInterrupt):
        run_store.drive(folder, 1, config.generations, stop_after(2))
    assert folder.done == 2
    same(finish(tmp_path, config.generations), whole)
    if changes:
        assert whole.curve[-1]["front_size"] >= 1 and whole.state["data"]["front"]


def test_an_interrupt_halfway_through_a_generation_keeps_what_landed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    config = resolve({**CONFIG, "population": 12})
    whole = library.evolve(config, workers=1)
    landed = RunDriver.batch
    calls: list[int] = []

    def interrupted(driver: RunDriver, generation: int, indices: list[int], result) -> None:  # type: ignore[no-untyped-def]
        landed(driver, generation, indices, result)
        calls.append(generation)
        if generation == 1:  # a batch of generation 1 landed, and was written
            raise KeyboardInterrupt

    monkeypatch.setattr(RunDriver, "batch", interrupted)
    monkeypatch.setattr(run_store, "SAVE_SECONDS", 0.0)  # every batch is written as it lands
    folder = run_store.new(tmp_path, config)
    with pytest.raises(KeyboardInterrupt):
        run_store.drive(folder, 1, config.generations, lambda step: None)
    monkeypatch.undo()
    assert folder.done == 1
    kept = folders.population(folder.db, folder.run_id, before=2, after=0)
    assert any(row.fitness is not None for row in kept)  # kept, not simulated again
    same(finish(tmp_path, config.generations), whole)


def test_files_wait_for_their_due_time_and_the_last_write_has_them_all(tmp_path: Path) -> None:
    config = resolve(CONFIG)
    folder = run_store.new(tmp_path, config)
    checkpoints = run_store.Checkpoints(folder, seconds=3600.0)
    run_store.drive(folder, 1, config.generations, lambda step: checkpoints.done())
    assert not (tmp_path / "state.json").exists()  # not due yet
    checkpoints.flush()
    assert json.loads((tmp_path / "state.json").read_text())["generation"] == 4
    assert json.loads((tmp_path / "cache.json").read_text())["generation"] == 4
    rows = (tmp_path / "population.csv").read_text().splitlines()
    assert len(rows) == 1 + 6 * 4 and rows[1].startswith("0,0,")


def test_a_folder_from_before_the_store_is_imported_and_goes_on(tmp_path: Path) -> None:
    config = resolve(CONFIG)
    whole_out = tmp_path / "whole"
    whole_out.mkdir()
    folder = run_store.new(whole_out, config)
    run_store.drive(folder, 1, config.generations, lambda step: None)
    whole = library.Result.of(run_store.Checkpoints(folder).flush())
    old = tmp_path / "old"  # what the release before the store left: its files alone
    old.mkdir()
    half = run_store.new(old, resolve({**CONFIG, "generations": 2}))
    run_store.drive(half, 1, 2, lambda step: None)
    run_store.Checkpoints(half).flush()
    half.db.dispose()
    for name in ("run.db", "run.db-wal", "run.db-shm"):
        (old / name).unlink(missing_ok=True)
    same(finish(old, config.generations), whole)
    for name in ("population.csv", "curve.csv", "curve.json", "best_robot.json", "state.json"):
        assert (old / name).read_bytes() == (whole_out / name).read_bytes(), name


def test_a_run_stopped_before_its_raised_generations_were_written_still_resumes(
    tmp_path: Path,
) -> None:
    """`--resume --generations G` raises the stored config's G at once; killed before the files
    were rewritten, config.json still says the old G, and the folder is not refused for it."""
    config = resolve({**CONFIG, "generations": 2})
    folder = run_store.new(tmp_path, config)
    run_store.drive(folder, 1, 2, lambda step: None)
    folders.take(folder.db, folder.run_id, "killed", 15.0, 3)  # then SIGKILL: no write after
    assert json.loads((tmp_path / "config.json").read_text())["generations"] == 2
    resumed = run_store.resume(tmp_path, None)
    assert resumed.config.generations == 3
    (tmp_path / "config.json").write_text(json.dumps({**config.to_json(), "seed": 4}))
    with pytest.raises(ValueError, match=r"config\.json: not the config of the run"):
        run_store.resume(tmp_path, None)


BEFORE_THE_STORE = Path(__file__).parent / "data" / "before_the_store"


def test_a_folder_written_by_the_release_before_the_store_goes_on_to_the_same_run(
    tmp_path: Path,
) -> None:
    """The files e5fd4bd wrote (`data/before_the_store/README.md`), resumed to 4 generations:
    every file as this release writes for the uninterrupted run."""
    old, whole_out = tmp_path / "old", tmp_path / "whole"
    shutil.copytree(BEFORE_THE_STORE, old)
    (old / "README.md").unlink()
    config = json.loads((old / "config.json").read_text())
    whole_out.mkdir()
    folder = run_store.new(whole_out, resolve({**config, "generations": 4}))
    run_store.drive(folder, 1, 4, lambda step: None)
    whole = library.Result.of(run_store.Checkpoints(folder).flush())
    same(finish(old, 4), whole)
    for name in ("population.csv", "curve.csv", "curve.json", "best_robot.json", "state.json"):
        assert (old / name).read_bytes() == (whole_out / name).read_bytes(), name


def test_an_append_cut_short_is_written_again_whole(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C in the middle of appending to population.csv: the interrupt's own flush writes
    the file again whole, never a row twice."""
    config = resolve(CONFIG)
    folder = run_store.new(tmp_path, config)
    checkpoints = run_store.Checkpoints(folder, seconds=3600.0)
    run_store.drive(folder, 1, 2, lambda step: None)
    checkpoints.flush()
    written = run_store.write_population

    def cut_short(out: Path, rows, append: bool = False) -> None:  # type: ignore[no-untyped-def]
        with (out / "population.csv").open("a") as handle:
            handle.write(f"2,0,{next(iter(rows))[2]},mutation\n")  # one row, then Ctrl-C
        raise KeyboardInterrupt

    run_store.drive(folder, 1, 4, lambda step: None)
    monkeypatch.setattr(run_store, "write_population", cut_short)
    with pytest.raises(KeyboardInterrupt):
        checkpoints.flush()
    monkeypatch.setattr(run_store, "write_population", written)
    checkpoints.flush()
    rows = (tmp_path / "population.csv").read_text().splitlines()[1:]
    assert len(rows) == len(set(rows)) == 6 * 4


def test_a_run_another_process_takes_over_stops_here(tmp_path: Path) -> None:
    config = resolve(CONFIG)
    folder = run_store.new(tmp_path, config)

    def report(step: Step) -> None:
        if step.stats.generation == 0:  # a second `softevo run --resume` on the folder
            folders.take(folder.db, folder.run_id, "another", 15.0, config.generations)

    with pytest.raises(run_store.TakenOverError):
        run_store.drive(folder, 1, config.generations, report)
    assert folder.done == 1  # the first process wrote nothing after it lost the run
