"""The files `softevo run` leaves in its output folder, rewritten after every generation so an
interrupted run still has its partial results:

    config.json       the resolved run configuration (preset merged with overrides)
    curve.csv         one row per generation (the learning curve)
    curve.json        {"run": config, "generations": [rows]}, the same as `softevo run --json`
    best_robot.json   the fastest robot so far, a softevo.robot/1 file
    state.json        the genetic algorithm's state (JSON), for inspection or resuming
"""

from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path
from typing import Any

from core.evolution import CURVE_COLUMNS, Evolution
from core.robot_file import robot_to_json


def summary(evolution: Evolution) -> dict[str, Any]:
    """The run's result as JSON: config, learning curve, best robot, counters."""
    best = evolution.best_robot()
    return {
        "run": evolution.config.to_json(),
        "generations": evolution.curve(),
        "best": None
        if best is None
        else {"speed": best[1], "generation": best[2], "robot": robot_to_json(best[0])},
        "evaluations": evolution.evaluations,
        "saved": evolution.saved,
        "wall_seconds": round(evolution.elapsed, 3),
    }


def _write_json(path: Path, data: Any) -> None:
    """Write atomically (temp file + rename) so a crash never leaves half a file."""
    temporary = path.with_suffix(path.suffix + ".tmp")
    temporary.write_text(json.dumps(data, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    os.replace(temporary, path)


def write_results(out: Path, evolution: Evolution) -> None:
    out.mkdir(parents=True, exist_ok=True)
    result = summary(evolution)
    _write_json(out / "config.json", result["run"])
    _write_json(out / "curve.json", {"run": result["run"], "generations": result["generations"]})
    _write_json(out / "state.json", evolution.algorithm.state.to_json())
    if result["best"] is not None:
        _write_json(out / "best_robot.json", result["best"]["robot"])
    temporary = out / "curve.csv.tmp"
    with temporary.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(CURVE_COLUMNS)
        for row in result["generations"]:
            writer.writerow(["" if v is None or (isinstance(v, float) and math.isnan(v)) else v
                             for v in (row[c] for c in CURVE_COLUMNS)])  # fmt: skip
    os.replace(temporary, out / "curve.csv")
