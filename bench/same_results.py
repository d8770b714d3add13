"""Every committed result re-checked: `python bench/same_results.py --tree OLD [--full]`.

A refactor of the search side must keep every run the same to the last digit. This runs one
short run of every preset, algorithm, encoding and descriptor set (and of every task) in this
checkout and in the checkout at `--tree` (an earlier commit in a `git worktree`), each in a
fresh interpreter, and compares the SHA-256 of their curves (every column, every digit), best
robots and archives. A column added since (`ADDED`, issue 51's normalised_hypervolume) is
hashed apart: compared where both trees have it, and named where only this one does. `--full`
also re-runs committed rows of `docs/experiments/results.csv` at their full length in this
checkout and compares their best speeds with the committed digits.
Prints one line per case and exits 1 on any difference.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from staged import stage

ROOT = Path(__file__).resolve().parent.parent
SHORT = {"population": 8, "generations": 4, "seed": 3, "sim": {"duration": 1.5, "settle_time": 0.5}}
CASES: dict[str, dict[str, Any]] = {
    **{
        preset: {"preset": preset, **SHORT}
        for preset in (
            "paper-voxel",
            "voxel-plus",
            "quick",
            "map-elites",
            "task-flat",
            "task-slope",
            "task-stairs",
            "task-rough",
            "task-hurdles",
        )
    },
    "paper-cube": {"preset": "paper-cube", **SHORT, "generations": 6},
    "random": {"preset": "quick", "algorithm": "random", **SHORT},
    "hillclimb": {"preset": "quick", "algorithm": "hillclimb", **SHORT},
    "tournament": {"preset": "quick", "selection": "tournament", **SHORT},
    "roulette": {"preset": "quick", "selection": "roulette", **SHORT},
    "heading-archive": {
        "preset": "quick",
        "algorithm": "map-elites",
        "descriptors": ["heading", "voxels"],
        "bins": [6, 4],
        **SHORT,
    },
    "ga+archive": {"preset": "quick", "descriptors": ["soft", "height"], "bins": [4, 4], **SHORT},
    "voxel-phase": {"preset": "map-elites", "encoding": "voxel-phase", "shape": [3, 3, 2], **SHORT},
    # the map-elites preset changed on purpose (issue 38); its old runs are this config
    "map-elites-old": {
        "preset": "paper-voxel",
        "algorithm": "map-elites",
        "descriptors": ["voxels", "actuated"],
        "bins": [8, 8],
        **SHORT,
    },
    "spring": {"preset": "quick", "encoding": "spring", "shape": [2, 2, 2], **SHORT},
    "efficiency": {"preset": "quick", "objective": "efficiency", **SHORT},
    # the strategies of issues 36-38 (skipped for a tree without them: NEWER)
    "nsga2": {"preset": "quick", "algorithm": "nsga2", "objectives": ["speed", "-energy"], **SHORT},
    "afpo": {"preset": "quick", "algorithm": "afpo", **SHORT},
    # a new nsga2/afpo run explores (issue 51); a stored one (read by `resolve`, not as a new
    # run) keeps the paper's operators: these must match the trees before it
    "nsga2-stored": {
        "preset": "quick",
        "algorithm": "nsga2",
        "objectives": ["speed", "-energy"],
        "_stored": True,
        **SHORT,
    },
    "afpo-stored": {"preset": "quick", "algorithm": "afpo", "_stored": True, **SHORT},
    # a config stored before objectives had an ideal (issue 51): it loads with the defaults
    "nsga2-no-ideal": {
        "preset": "quick",
        "algorithm": "nsga2",
        "objectives": [
            {"measure": "speed", "goal": "max", "reference": 0.0},
            {"measure": "energy", "goal": "min", "reference": 1_000_000.0},
        ],
        "_stored": True,
        **SHORT,
    },
    "steady-state": {"preset": "quick", "algorithm": "steady-state", **SHORT},
    "steady-archive": {
        "preset": "quick",
        "algorithm": "steady-state",
        "descriptors": ["voxels", "actuated"],
        "bins": [4, 4],
        "options": {"parents": "archive"},
        **SHORT,
    },
    "cppn": {"preset": "quick", "encoding": "cppn", "shape": [4, 4, 4], **SHORT},
}

NEWER = {
    "nsga2",
    "afpo",
    "nsga2-stored",
    "afpo-stored",
    "nsga2-no-ideal",
    "steady-state",
    "steady-archive",
    "cppn",
}

ONE = """
import hashlib, json, sys
from pathlib import Path
if len(sys.argv) > 2:  # a staged tree: its own strategies, not the installed checkout's
    sys.path.insert(0, sys.argv[3])
    from staged import own_strategies
    own_strategies(Path(sys.argv[2]))
from softevo import library
PROFILE_SETTINGS = ("profile", "drag", "material_damping", "contact_damping", "dt_fraction")
config = json.loads(sys.argv[1])
if config.pop("_stored", False):  # a stored config, as a resumed run reads it
    from softevo.core.config import resolve
    config = resolve(config)
result = library.evolve(config, workers=1)
digest = lambda value: hashlib.sha256(json.dumps(value, sort_keys=True).encode()).hexdigest()[:16]
ADDED = ("normalised_hypervolume",)  # columns newer than some trees: hashed apart
curve = [{k: v for k, v in row.items() if k not in ADDED} for row in result.curve]
added = [{k: row[k] for k in ADDED if k in row} for row in result.curve]
best = result.best
if best and best.get("sim", {}).get("profile", "paper") == "paper":  # the paper's own settings:
    sim = {k: v for k, v in best["sim"].items() if k not in PROFILE_SETTINGS}  # those of a tree
    best = {**best, "sim": sim}  # before profiles, whose values in this profile are its zeros
print(json.dumps({"curve": digest(curve), "best": digest(best),
                  "added": digest(added) if any(added) else None,
                  "archive": digest(result.archive), "last": result.curve[-1]}))
"""


def run(config: dict[str, Any], path: Path | None) -> dict[str, Any]:
    env, staged = dict(os.environ), []
    if path is not None:
        env["PYTHONPATH"] = str(path)
        staged = [str(path), str(Path(__file__).resolve().parent)]
    done = subprocess.run(
        [sys.executable, "-c", ONE, json.dumps(config), *staged],
        capture_output=True,
        text=True,
        env=env,
        cwd=tempfile.gettempdir(),
        check=False,
    )
    if done.returncode != 0:
        raise SystemExit(f"{config}: {done.stderr.strip().splitlines()[-1]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def compare_trees(old: Path, new: Path | None) -> int:
    staged, against = stage(old), None if new is None else stage(new)
    differences = 0
    try:
        for name, config in CASES.items():
            try:
                before = run(config, staged)
            except SystemExit as error:
                if name not in NEWER:
                    raise
                print(f"{name:16} not in --tree ({error})")
                continue
            after = run(config, against)
            keys = ["curve", "best", "archive"] + (["added"] if before.get("added") else [])
            differ = [key for key in keys if before[key] != after[key]]
            differences += bool(differ)
            verdict = "same" if not differ else "DIFFERENT " + ",".join(differ)
            if after.get("added") and not before.get("added"):
                verdict += " (+ normalised_hypervolume, new here)"
            print(
                f"{name:16} {verdict}  curve {after['curve']}  "
                f"best so far {after['last']['best_so_far']!r}"
            )
    finally:
        for folder in (staged, against):
            if folder is not None:
                shutil.rmtree(folder, ignore_errors=True)
    return differences


def committed_rows(limit: int) -> int:
    """The committed boxes rows' seeds at full length, against their committed digits."""
    differences = 0
    with (ROOT / "docs" / "experiments" / "results.csv").open() as handle:
        rows = [row for row in csv.DictReader(handle) if row["experiment"] == "boxes"]
    for row in rows[:limit]:
        shape = [int(side) for side in row["shape"].split("x")]
        for item in row["best_by_seed"].split():
            seed, best = item.split(":")
            config = {"preset": row["variant"], "shape": shape, "seed": int(seed)}
            found = run(config, None)["last"]["best_so_far"]
            same = f"{found:.6g}" == best
            differences += not same
            print(
                f"{row['variant']} {row['shape']} seed {seed}: committed {best}, now "
                f"{found:.6g} {'same' if same else 'DIFFERENT'}"
            )
    return differences


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", type=Path, required=True, help="the earlier checkout")
    parser.add_argument(
        "--against", type=Path, help="compare with this checkout instead of the installed one"
    )
    parser.add_argument(
        "--full",
        type=int,
        default=0,
        metavar="ROWS",
        help="also re-run this many committed boxes rows at full length",
    )
    args = parser.parse_args()
    digest = hashlib.sha256(json.dumps(CASES, sort_keys=True).encode()).hexdigest()[:8]
    print(f"{len(CASES)} cases ({digest}), {args.tree} against {args.against or 'this checkout'}")
    differences = compare_trees(args.tree, args.against)
    if args.full:
        differences += committed_rows(args.full)
    print("every result the same" if differences == 0 else f"{differences} differences")
    return 1 if differences else 0


if __name__ == "__main__":
    raise SystemExit(main())
