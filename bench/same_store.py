"""`softevo run`'s store path against the run in memory: `python bench/same_store.py [--workers W]`.

`softevo run` keeps its run in the service's store (`softevo.run_store`: SQLite in the output
folder, the service's `RunDriver`); the library holds a run in memory (`Evolution`), as
`softevo run` did before. Both run the one generation step, so every result must be the same.
This runs every case of `same_results.py` (every preset, algorithm, encoding and descriptor set,
every task) both ways in this checkout and compares the `Result`s field by field: curve, best
robot, archive, GA state, counts, records of measures and front. Prints one line per case and
exits 1 on any difference.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from same_results import CASES

from softevo import library, run_store
from softevo.core.config import RunConfig, resolve

FIELDS = (
    "config",
    "curve",
    "best",
    "best_fitness",
    "best_generation",
    "state",
    "archive",
    "evaluations",
    "saved",
    "measures",
    "best_measures",
    "front",
)
#: steady-state with a window of two populations, besides same_results' cases
EXTRA = {"steady-window": {**CASES["steady-state"], "options": {"window": 16}}}


def through_the_store(config: RunConfig, workers: int) -> library.Result:
    with tempfile.TemporaryDirectory() as out:
        folder = run_store.new(Path(out), config)
        run_store.drive(folder, workers, config.generations, lambda step: None)
        result = library.Result.of(run_store.evolution(folder))
        folder.close()
        return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2, help="the store path's processes (2)")
    args = parser.parse_args()
    differences = 0
    for name, case in {**CASES, **EXTRA}.items():
        config = resolve(case)
        stored = through_the_store(config, args.workers)
        in_memory = library.evolve(config, workers=1)
        different = [f for f in FIELDS if getattr(stored, f) != getattr(in_memory, f)]
        differences += bool(different)
        print(f"{name:16} {'same' if not different else 'DIFFERENT: ' + ', '.join(different)}")
    print("every result the same" if not differences else f"{differences} differences")
    return 1 if differences else 0


if __name__ == "__main__":
    raise SystemExit(main())
