"""`softevo run` as a user runs it: `main(argv)` in process (a real process where Ctrl-C is the
point), its files and its JSON."""

from __future__ import annotations

import csv
import json
import os
import signal
import sqlite3
import subprocess
import sys
import time
from pathlib import Path
from xml.etree import ElementTree

import pytest
from sqlalchemy.exc import OperationalError

from softevo.api import store
from softevo.api.store import driving
from softevo.core.config import RunConfig
from softevo.core.robots.robot_file import load_robot
from softevo.run_config import config_hash
from tests.softevo.inprocess import softevo


def test_run_writes_results_and_prints_json(tmp_path: Path) -> None:
    out = tmp_path / "run"
    done = softevo(
        "run",
        "--preset",
        "quick",
        "--generations",
        "4",
        "--population",
        "8",
        "--seed",
        "5",
        "--workers",
        "1",
        "--out",
        str(out),
        "--json",
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    rows = result["generations"]
    assert [row["generation"] for row in rows] == [0, 1, 2, 3]
    assert set(rows[0]) >= {"best", "mean", "median", "min", "best_so_far", "diversity"}
    assert result["run"]["seed"] == 5 and result["out"] == str(out)
    with (out / "curve.csv").open() as handle:
        table = list(csv.DictReader(handle))
    assert len(table) == 4 and float(table[-1]["best_so_far"]) == rows[-1]["best_so_far"]
    assert json.loads((out / "curve.json").read_text())["generations"] == rows
    best = load_robot(out / "best_robot.json")
    assert best.shape == (3, 3, 3)
    assert result["best"]["speed"] == rows[-1]["best_so_far"]
    again = softevo(
        "run",
        "--preset",
        "quick",
        "--generations",
        "4",
        "--population",
        "8",
        "--seed",
        "5",
        "--workers",
        "2",
        "--out",
        str(tmp_path / "again"),
        "--json",
    )
    assert json.loads(again.stdout)["generations"] == rows
    # every individual, and the figures
    with (out / "population.csv").open() as handle:
        population = list(csv.DictReader(handle))
    assert len(population) == 4 * 8
    assert max(float(p["fitness"]) for p in population if p["fitness"]) == rows[-1]["best_so_far"]
    for name in ("curve.png", "population.png", "diversity.png"):
        assert (out / name).read_bytes()[:4] == b"\x89PNG"


def test_plot_draws_a_results_folder_and_refuses_what_is_not_one(tmp_path: Path) -> None:
    out = tmp_path / "run"
    run = ("run", "--preset", "quick", "--generations", "3", "--population", "6", "--workers", "1")
    assert softevo(*run, "--out", str(out)).returncode == 0
    for kind in ("all", "curve", "population", "diversity"):
        figure = tmp_path / f"{kind}.png"
        done = softevo("plot", str(out), "--out", str(figure), "--kind", kind)
        assert done.returncode == 0, done.stderr
        assert figure.read_bytes()[:4] == b"\x89PNG" and figure.stat().st_size > 10_000
    pdf, svg = tmp_path / "x.pdf", tmp_path / "x.svg"  # the suffix picks the format
    assert softevo("plot", str(out), "--out", str(pdf)).returncode == 0
    assert pdf.read_bytes()[:4] == b"%PDF"
    assert softevo("plot", str(out), "--out", str(svg), "--kind", "curve").returncode == 0
    root = ElementTree.parse(svg).getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    assert "best so far" in svg.read_text()  # the legend's text
    jpeg = softevo("plot", str(out), "--out", str(tmp_path / "x.jpg"))
    assert jpeg.returncode == 2 and ".png, .pdf, .svg" in jpeg.stderr
    assert not (tmp_path / "x.jpg").exists()
    bad = softevo("plot", str(tmp_path / "nothing-here"), "--out", str(tmp_path / "x.png"))
    assert bad.returncode == 1 and "neither a results folder nor a run id" in bad.stderr
    away = softevo("plot", "3", "--url", "http://127.0.0.1:9", "--out", str(tmp_path / "y.png"))
    assert away.returncode == 1 and "cannot read run 3" in away.stderr


def test_bad_arguments_give_one_line_and_exit_2(tmp_path: Path) -> None:
    for args, words in [
        (["--population", "1"], "population"),
        (["--shape", "5x5"], "shape"),
        (["--preset", "nope"], "--preset"),
        (["--workers", "0"], "--workers"),
        (["--generations", "x"], "--generations"),
        (["--out", "/proc/softevo"], "cannot write"),
    ]:
        done = softevo("run", "--out", str(tmp_path / "x"), *args)
        assert done.returncode == 2, (args, done.stderr)
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and words in lines[0], done.stderr


#: Starts the command in argv[1:] the way an interactive shell starts a foreground program:
#: SIGINT at its default and not blocked (both are inherited across exec, and a Python started
#: with SIGINT ignored never installs its KeyboardInterrupt handler).
AS_A_SHELL_STARTS_IT = (
    "import os, signal, sys; signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT}); "
    "signal.signal(signal.SIGINT, signal.SIG_DFL); os.execv(sys.argv[1], sys.argv[1:])"
)


def _signals(pid: int) -> str:
    """The process's blocked, ignored and caught signal masks, as Linux's /proc shows them."""
    try:
        lines = Path(f"/proc/{pid}/status").read_text().splitlines()
    except OSError as error:  # no /proc here, or the process already gone
        return f"no signal masks ({type(error).__name__})"
    return ", ".join(line for line in lines if line.startswith(("SigBlk", "SigIgn", "SigCgt")))


def test_ctrl_c_stops_cleanly_and_keeps_partial_results(tmp_path: Path) -> None:
    out = tmp_path / "interrupted"
    command = [
        sys.executable,
        "-P",
        "-c",
        AS_A_SHELL_STARTS_IT,
        sys.executable,
        "-P",
        "-m",
        "softevo.cli",
        "run",
        "--preset",
        "paper-voxel",
        "--workers",
        "2",
        "--out",
        str(out),
    ]
    process = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True
    )
    started = time.monotonic()
    while not (out / "curve.csv").exists() and time.monotonic() < started + 120:
        time.sleep(0.1)
    seen = f"curve.csv seen after {time.monotonic() - started:.1f} s; {_signals(process.pid)}"
    os.killpg(process.pid, signal.SIGINT)  # what Ctrl-C does: the whole process group
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 130, f"{seen}\n{stderr}"
    assert f"partial results and figures in {out}/" in stderr
    assert f"softevo run --resume {out}" in stderr
    rows = list(csv.DictReader((out / "curve.csv").open()))
    assert 1 <= len(rows) < 100
    for name in ("curve.png", "population.png", "diversity.png"):  # of the generations done
        assert (out / name).read_bytes()[:4] == b"\x89PNG"
    assert load_robot(out / "best_robot.json").shape == (4, 4, 4)
    wal = out / "run.db-wal"  # the store's log moved into run.db: one file to copy
    assert not wal.exists() or wal.stat().st_size == 0


SMALL = ("--preset", "quick", "--population", "6", "--duration", "1", "--workers", "1")


def test_default_folder_names_the_config_and_another_configs_folder_is_refused(
    tmp_path: Path,
) -> None:
    for shape in ("2x2x2", "3x2x2"):
        done = softevo("run", *SMALL, "--generations", "1", "--shape", shape, cwd=tmp_path)
        assert done.returncode == 0, done.stderr
    folders = sorted(p.name for p in (tmp_path / "softevo-runs").iterdir())
    assert len(folders) == 2, folders  # the second run did not overwrite the first
    assert [f.rsplit("-", 1)[0] for f in folders] == [
        "quick-2x2x2-ga-voxel-seed0",
        "quick-3x2x2-ga-voxel-seed0",
    ]
    for folder in folders:
        config = json.loads((tmp_path / "softevo-runs" / folder / "config.json").read_text())
        assert "x".join(map(str, config["shape"])) == folder.split("-")[1]
        assert folder.endswith(config_hash(RunConfig.model_validate(config)))
    taken = tmp_path / "softevo-runs" / folders[0]
    refused = softevo("run", *SMALL, "--generations", "1", "--shape", "3x2x2", "--out", str(taken))
    assert refused.returncode == 2 and "holds the results of another config" in refused.stderr
    assert json.loads((taken / "config.json").read_text())["shape"] == [2, 2, 2]


def test_resume_goes_on_to_the_curve_of_an_uninterrupted_run(tmp_path: Path) -> None:
    whole, stopped = tmp_path / "whole", tmp_path / "stopped"
    run = ("run", *SMALL, "--shape", "2x2x2", "--seed", "3")
    assert softevo(*run, "--generations", "5", "--out", str(whole)).returncode == 0
    assert softevo(*run, "--generations", "2", "--out", str(stopped)).returncode == 0
    resumed = softevo("run", "--resume", str(stopped), "--generations", "5", "--json")
    assert resumed.returncode == 0, resumed.stderr
    rows = json.loads(resumed.stdout)["generations"]
    expected = json.loads((whole / "curve.json").read_text())
    assert rows == expected["generations"] and len(rows) == 5
    assert json.loads((stopped / "config.json").read_text()) == expected["run"]
    assert (stopped / "curve.csv").read_text() == (whole / "curve.csv").read_text()
    assert (stopped / "population.csv").read_text() == (whole / "population.csv").read_text()
    again = softevo("run", "--resume", str(stopped), "--shape", "3x3x3")
    assert again.returncode == 2 and "drop --shape" in again.stderr
    nothing = softevo("run", "--resume", str(tmp_path / "nowhere"))
    assert nothing.returncode == 2 and "not a resumable" in nothing.stderr


def _committed(store: Path) -> int:
    """Generations run.db holds committed (0 while it is being made)."""
    try:
        with sqlite3.connect(f"file:{store}?mode=ro", uri=True, timeout=5) as connection:
            row = connection.execute("SELECT max(generations_done) FROM runs").fetchone()
    except sqlite3.Error:
        return 0
    return row[0] or 0


def test_sigkill_then_resume_takes_the_run_over_to_the_uninterrupted_curve(
    tmp_path: Path,
) -> None:
    """No chance to save anything: `--resume` takes the run over from run.db as a restarted
    service takes over a run whose driver died (the same code)."""
    whole, killed = tmp_path / "whole", tmp_path / "killed"
    # 3x3x3 (not 2x2x2, whose few bodies the cache soon answers): generations that take time, so
    # the kill lands between the second and the last
    run = ("run", *SMALL, "--shape", "3x3x3", "--seed", "4", "--generations", "20")
    assert softevo(*run, "--out", str(whole)).returncode == 0
    command = [sys.executable, "-P", "-m", "softevo.cli", *run, "--out", str(killed)]
    process = subprocess.Popen(
        command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True
    )
    started = time.monotonic()
    while _committed(killed / "run.db") < 2 and time.monotonic() < started + 120:
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGKILL)
    process.communicate(timeout=60)
    done = _committed(killed / "run.db")
    assert 2 <= done < 20, done
    resumed = softevo("run", "--resume", str(killed), "--json")
    assert resumed.returncode == 0, resumed.stderr
    expected = json.loads((whole / "curve.json").read_text())["generations"]
    assert json.loads(resumed.stdout)["generations"] == expected
    assert (killed / "population.csv").read_text() == (whole / "population.csv").read_text()


def test_a_store_that_cannot_write_is_said_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "full"

    def full(*args: object) -> None:
        raise OperationalError("INSERT", {}, sqlite3.OperationalError("database or disk is full"))

    monkeypatch.setattr(driving, "commit_generation", full)
    done = softevo("run", *SMALL, "--shape", "2x2x2", "--generations", "2", "--out", str(out))
    assert done.returncode == 1 and "Traceback" not in done.stderr
    said = done.stderr.strip().splitlines()[-1]
    assert said == (
        f"softevo run: error: {out}/run.db: database or disk is full; what was "
        f"committed is kept, go on with: softevo run --resume {out}"
    )
    monkeypatch.undo()
    resumed = softevo("run", "--resume", str(out), "--json")
    assert resumed.returncode == 0 and len(json.loads(resumed.stdout)["generations"]) == 2


def test_a_store_that_cannot_start_is_said_in_one_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def full(*args: object) -> None:
        raise OperationalError("INSERT", {}, sqlite3.OperationalError("database or disk is full"))

    monkeypatch.setattr(store, "create_run", full)
    out = tmp_path / "full"
    done = softevo("run", *SMALL, "--generations", "1", "--out", str(out))
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert (
        done.stderr.strip()
        .splitlines()[-1]
        .endswith(f"--out {out}: cannot start the run's store (database or disk is full)")
    )


def test_another_configs_store_is_refused_without_its_config_json(tmp_path: Path) -> None:
    out = tmp_path / "taken"
    run = ("run", *SMALL, "--shape", "2x2x2", "--generations", "1", "--out", str(out))
    assert softevo(*run).returncode == 0
    (out / "config.json").unlink()
    refused = softevo(*run, "--seed", "9")
    assert refused.returncode == 2 and "holds the results of another config" in refused.stderr
    assert (out / "run.db").is_file() and softevo("run", "--resume", str(out)).returncode == 0


def test_a_folder_of_the_same_config_stored_before_ideals_is_not_anothers(tmp_path: Path) -> None:
    """A config stored before objectives had an ideal reads, as this version reads it, as the
    same config: its folder is run again, not refused as another config's."""
    out = tmp_path / "before-ideals"
    run = ("run", *SMALL, "--shape", "2x2x2", "--generations", "1", "--out", str(out))
    run += ("--algorithm", "nsga2", "--objectives", "speed,-cost_of_transport")
    assert softevo(*run).returncode == 0
    stored = json.loads((out / "config.json").read_text())
    assert all("ideal" in spec for spec in stored["objectives"])
    for spec in stored["objectives"]:
        del spec["ideal"]
    (out / "config.json").write_text(json.dumps(stored))
    again = softevo(*run)
    assert again.returncode == 0, again.stderr
    refused = softevo(*run, "--seed", "9")  # another config is still refused
    assert refused.returncode == 2 and "holds the results of another config" in refused.stderr
