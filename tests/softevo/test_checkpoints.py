"""`softevo run`'s files are rewritten at most every SAVE_SECONDS and when the run stops; population
rows go out after every generation; an interrupt halfway through a step writes the last whole
generation, from which a resumed run goes on to the uninterrupted curve and counts."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from softevo import results
from softevo.core.config import resolve
from softevo.core.physics.evaluation import SerialEvaluator
from softevo.core.search.evolution import Evolution
from softevo.results import Checkpoints, read_resumable

CONFIG = {"preset": "quick", "population": 6, "generations": 4, "seed": 3, "shape": [2, 2, 2],
          "sim": {"duration": 1.0}}  # fmt: skip


def generations_in_population(out: Path) -> list[int]:
    with (out / "population.csv").open(newline="", encoding="utf-8") as handle:
        return sorted({int(row["generation"]) for row in csv.DictReader(handle)})


#: NSGA-II and AFPO with objectives: their kept values, births, lineages and the front so far
#: ride in the state, and must come back from the files as they were.
PARETO = {"objectives": ["speed", "-cost_of_transport"]}


@pytest.mark.parametrize(
    "changes",
    [{}, {"algorithm": "nsga2", **PARETO}, {"algorithm": "afpo", **PARETO}],
    ids=["ga", "nsga2", "afpo"],
)
def test_an_interrupt_writes_the_last_whole_generation_and_resuming_goes_on(
    tmp_path: Path, changes: dict
) -> None:
    config = resolve({**CONFIG, **changes})
    whole = Evolution.start(config)
    whole.run(SerialEvaluator())
    evolution, evaluator = Evolution.start(config), SerialEvaluator()
    checkpoints = Checkpoints(tmp_path, evolution, seconds=3600.0)
    for _ in range(2):
        evolution.step(evaluator)
        checkpoints.done()
    assert not (tmp_path / "state.json").exists()  # not due yet
    assert generations_in_population(tmp_path) == [0, 1]  # every generation as it ends

    evolution.step(evaluator)  # a third step, then interrupted before its `done`: what the
    evolution.evaluations += 1000  # files get is generation 2's, not the live run's
    checkpoints.flush()
    cache = json.loads((tmp_path / "cache.json").read_text())
    assert cache["generation"] == 2
    assert len(json.loads((tmp_path / "curve.json").read_text())["generations"]) == 2

    resumed = read_resumable(tmp_path, 4)
    resumed.run(SerialEvaluator())
    assert resumed.curve() == whole.curve()
    assert (resumed.evaluations, resumed.saved) == (whole.evaluations, whole.saved)
    assert resumed.state.data == whole.state.data  # the front so far, and what breeding reads
    if changes:
        assert whole.curve()[-1]["front_size"] >= 1 and whole.state.data["front"]


def test_due_checkpoints_write_every_file(tmp_path: Path) -> None:
    evolution = Evolution.start(resolve(CONFIG))
    checkpoints = Checkpoints(tmp_path, evolution, seconds=0.0)
    evolution.step(SerialEvaluator())
    checkpoints.done()
    assert json.loads((tmp_path / "cache.json").read_text())["generation"] == 1
    checkpoints.flush()  # nothing newer to write
    assert json.loads((tmp_path / "state.json").read_text())["generation"] == 1


def test_an_interrupt_during_a_write_leaves_the_whole_generation_to_flush(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    evolution = Evolution.start(resolve(CONFIG))
    checkpoints = Checkpoints(tmp_path, evolution, seconds=0.0)
    evolution.step(SerialEvaluator())

    def interrupted(out: Path, run: Evolution) -> None:
        (out / "cache.json").write_text('{"generation": -1}')  # half a write
        raise KeyboardInterrupt

    monkeypatch.setattr(results, "write_results", interrupted)
    with pytest.raises(KeyboardInterrupt):
        checkpoints.done()
    monkeypatch.undo()
    checkpoints.flush()
    assert json.loads((tmp_path / "cache.json").read_text())["generation"] == 1
    assert read_resumable(tmp_path).state.generation == 1
