"""`softevo run --resume DIR` on a folder that was tampered with: each case ends in one line
naming the file, before anything runs, and none is silently accepted (issue 39). A folder of the
release before the store (its files, no run.db) is checked file by file before it is imported;
one with a store is checked against it. The untouched folders still resume."""

from __future__ import annotations

import json
import shutil
import sqlite3
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests.softevo.inprocess import softevo

Files = dict[str, Any]  # config, state, cache as parsed JSON


@pytest.fixture(scope="module")
def finished(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished 2-generation run of 8 small robots, resumed to 3 generations in the tests."""
    out = tmp_path_factory.mktemp("run") / "run"
    done = softevo(
        "run",
        "--preset",
        "quick",
        "--population",
        "8",
        "--generations",
        "2",
        "--shape",
        "2x2x2",
        "--duration",
        "0.6",
        "--out",
        str(out),
    )
    assert done.returncode == 0, done.stderr
    return out


@pytest.fixture(scope="module")
def before_the_store(finished: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The same run as the release before the store left it: its files alone."""
    out = tmp_path_factory.mktemp("old") / "run"
    shutil.copytree(finished, out)
    (out / "run.db").unlink()
    return out


def _individual(files: Files) -> dict[str, Any]:
    return files["state"]["previous"][0]


def _set(path: str, value: Any) -> Callable[[Files], None]:
    """A change of one field, `file.key.key` (numbers index lists)."""

    def change(files: Files) -> None:
        *keys, last = path.split(".")
        target: Any = files
        for key in keys:
            target = target[int(key)] if isinstance(target, list) else target[key]
        if isinstance(target, list):
            target[int(last)] = value
        else:
            target[last] = value

    return change


def _both_generations(value: int) -> Callable[[Files], None]:
    def change(files: Files) -> None:
        files["state"]["generation"] = files["cache"]["generation"] = value

    return change


def _shorten_fitness(files: Files) -> None:
    files["state"]["previous_fitness"] = files["state"]["previous_fitness"][:3]


DEEP = "[" * 100_000 + "]" * 100_000
HEAD, ROW = "generation,index,fitness", "0,0,0.1,random\n"

CASES: dict[str, tuple[Callable[[Files], None] | tuple[str, str], str]] = {
    "negative generation": (_both_generations(-1), "generation"),
    "short genome": (_set("state.previous.0.genome.discrete", [1, 2]), "genome"),
    "foreign genome": (_set("state.previous.0.genome.encoding", "spring"), "encoding"),
    "gene out of its alphabet": (_set("state.previous.0.genome.discrete.0", 99), "alphabet"),
    "fractional gene": (_set("state.previous.0.genome.discrete.0", 1.5), "discrete"),
    "real gene 1e308": (_set("state.previous.0.genome.real.0", 1e308), "real"),
    "parents ab": (_set("state.previous.0.parents", "ab"), "parents"),
    "parent past the generation": (_set("state.previous.0.parents", [99]), "parents"),
    "operator a number": (_set("state.previous.0.operator", 5), "operator"),
    "another config's shape": (_set("config.shape", [3, 3, 3]), "genome"),
    "another config's encoding": (_set("config.encoding", "voxel-phase"), "genome"),
    "another config's seed": (_set("config.seed", 5), "seed"),
    "population 8 to 16": (_set("config.population", 16), "population"),
    "previous_fitness shortened": (_shorten_fitness, "previous_fitness"),
    "fitness a string": (_set("state.previous_fitness.0", "fast"), "previous_fitness"),
    "best genome foreign": (_set("state.best.genome.encoding", "cube-springs"), "best"),
    "history not a list": (_set("state.history", 5), "history"),
    "state a list": (("state.json", "[]"), "state.json"),
    "state a string": (("state.json", '"state"'), "state.json"),
    "cache a list": (("cache.json", "[1, 2]"), "cache.json"),
    "cache fitness a list": (_set("cache.fitness", []), "fitness"),
    "cache elapsed negative": (_set("cache.elapsed", -5), "elapsed"),
    "config a list": (("config.json", "[]"), "config.json"),
    "state nested 100k deep": (("state.json", DEEP), "nested"),
    "cache nested 100k deep": (("cache.json", DEEP), "nested"),
    "config nested 100k deep": (("config.json", DEEP), "nested"),
    "state not JSON": (("state.json", "{"), "JSON"),
    "population.csv garbled": (("population.csv", "generation\nx,y\n"), "population.csv"),
    "population.csv header misspelt": (
        ("population.csv", f"{HEAD}nes,operator\n0,0,1,r\n"),
        "population.csv",
    ),
    "population.csv row cut": (("population.csv", f"{HEAD},operator\n0\n"), "population.csv"),
    "population.csv row twice": (("population.csv", f"{HEAD},operator\n{ROW}{ROW}"), "twice"),
    "population.csv fitness a word": (
        ("population.csv", f"{HEAD},operator\n0,0,fast,r\n"),
        "population.csv",
    ),
    "population.csv a cell too many": (
        ("population.csv", f"{HEAD},operator\n0,0,1,r,9\n"),
        "population.csv",
    ),
    "previous null": (_set("state.previous", None), "previous"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_tampered_folder_is_refused_in_one_line(
    before_the_store: Path, tmp_path: Path, case: str
) -> None:
    folder = tmp_path / "run"
    shutil.copytree(before_the_store, folder)
    change, words = CASES[case]
    if isinstance(change, tuple):
        (folder / change[0]).write_text(change[1])
    else:
        files = {
            name: json.loads((folder / f"{name}.json").read_text())
            for name in ("config", "state", "cache")
        }
        change(files)
        for name, data in files.items():
            (folder / f"{name}.json").write_text(json.dumps(data))
    before = (folder / "population.csv").read_bytes()
    done = softevo("run", "--resume", str(folder), "--generations", "3")
    assert done.returncode == 2, (done.returncode, done.stderr)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert "--resume" in lines[0] and words in lines[0], lines[0]
    assert (folder / "population.csv").read_bytes() == before  # nothing written
    assert not (folder / "run.db").exists()


def _write(name: str, text: str) -> Callable[[Path], None]:
    return lambda folder: (folder / name).write_text(text)


def _sql(*statements: str) -> Callable[[Path], None]:
    def change(folder: Path) -> None:
        with sqlite3.connect(folder / "run.db") as connection:
            for statement in statements:
                connection.execute(statement)
        connection.close()

    return change


def _directory(folder: Path) -> None:
    (folder / "run.db").unlink()
    (folder / "run.db").mkdir()


STORE_CASES: dict[str, tuple[Callable[[Path], None], str]] = {
    "config.json edited": (
        _write("config.json", '{"preset": "quick"}'),
        "config.json: not the config of the run",
    ),
    "run.db garbled": (
        _write("run.db", "not a database " * 100),
        "run.db: not a `softevo run` store",
    ),
    "run.db a folder": (_directory, "run.db: not a file"),
    "run.db of a newer release": (
        _sql("UPDATE alembic_version SET version_num = '9999'"),
        "run.db: written by another release",
    ),
    "run.db of another program": (_sql("DROP TABLE alembic_version"), "holds other tables"),
    "state without a seed": (
        _sql("""UPDATE runs SET ga_state = '{"x": 1}'"""),
        "run.db: not a run to go on with",
    ),
    "config a word for a count": (
        _sql("""UPDATE runs SET config = json_set(config, '$.population', 'many')"""),
        "run.db: population",
    ),
}


@pytest.mark.parametrize("case", list(STORE_CASES))
def test_a_folder_at_odds_with_its_store_is_refused_in_one_line(
    finished: Path, tmp_path: Path, case: str
) -> None:
    folder = tmp_path / "run"
    shutil.copytree(finished, folder)
    change, words = STORE_CASES[case]
    change(folder)
    if case == "config a word for a count":
        (folder / "config.json").unlink()  # else it is refused for differing from it
    before = (folder / "population.csv").read_bytes()
    done = softevo("run", "--resume", str(folder), "--generations", "3")
    assert done.returncode == 2, (done.returncode, done.stderr)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert lines[0].startswith(f"softevo run: error: --resume {folder}") and words in lines[0]
    assert (folder / "population.csv").read_bytes() == before  # nothing written


def test_too_many_generations_are_refused_and_the_folder_still_resumes(
    finished: Path, tmp_path: Path
) -> None:
    folder = tmp_path / "run"
    shutil.copytree(finished, folder)
    refused = softevo("run", "--resume", str(folder), "--generations", "100000000")
    assert refused.returncode == 2 and "Traceback" not in refused.stderr, refused.stderr
    assert "run.db: generations:" in refused.stderr
    for generations in ("0", "-1"):
        refused = softevo("run", "--resume", str(folder), "--generations", generations)
        assert refused.returncode == 2 and "generations" in refused.stderr, refused.stderr
    done = softevo("run", "--resume", str(folder), "--generations", "3")
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize("kind", ["finished", "before_the_store"])
def test_the_untouched_folders_resume_to_the_same_files(
    request: pytest.FixtureRequest, tmp_path: Path, kind: str
) -> None:
    folder = tmp_path / "run"
    shutil.copytree(request.getfixturevalue(kind), folder)
    done = softevo("run", "--resume", str(folder), "--generations", "3")
    assert done.returncode == 0, done.stderr
    assert json.loads((folder / "state.json").read_text())["generation"] == 3
    assert (folder / "run.db").is_file()


def test_a_file_instead_of_a_folder_is_refused_in_one_line(finished: Path) -> None:
    done = softevo("run", "--resume", str(finished / "config.json"))
    assert done.returncode == 2 and "not a folder" in done.stderr, done.stderr
