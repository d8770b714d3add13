"""`softevo reproduce`: the paper's experiments, and past them, run through the service's API.

Everything that evolves goes through the REST API: the nine bounding boxes as one sweep
(`POST /sweeps`), the phase 2 cube, the baselines (random search and a hill climber on the GA's
measured evaluation budget), the `spring` encoding against `voxel`, and an ablation of the
paper's GA settings. Without `--url` a private `softevo serve` (SQLite in the output folder, the
in-process pool on every core) is started and stopped here. Phase 1, the breathing cube, is one
robot, not an evolution: it is simulated in this process with `softevo.core.physics`.

Outputs in `--out`: results.csv and results.md (one row per experiment, variant and box: best
speed over seeds, best within the GA's simulation budget, evaluations, wall time), the figures as
PNG, and softevo.db with every genome. `--resume` reuses the runs a previous invocation left in
that database (or in the `--url` service) and submits only what is missing, so an interrupted
reproduction goes on where it stopped, and the tables and figures can be redrawn from finished
runs without simulating anything again (every run is deterministic in its config and seed).
"""

from __future__ import annotations

import argparse
from typing import Any

from softevo.command_error import CommandError
from softevo.service_commands import need_service


def add_parser(commands: Any) -> None:
    parser = commands.add_parser(
        "reproduce",
        help="re-run the paper's experiments (and baselines, encodings, an ablation) via the API",
        description=(
            "Run the paper's nine bounding boxes (paper-voxel, seeds 1-3, one sweep), its phase "
            "2 cube and phase 1 breathing cube, random search and hill-climber baselines on the "
            "GA's evaluation budget, the spring encoding against voxel, and an ablation of the "
            "GA's settings, all through the REST API; write results.csv, results.md and the "
            "figures into --out. --quick runs a tiny version of all of it in under a minute."
        ),
    )
    parser.add_argument("--quick", action="store_true", help="tiny settings, same code path")
    parser.add_argument(
        "--tasks",
        action="store_true",
        help="run the task suite instead (task-flat, -slope, -stairs, -rough, -hurdles x seeds "
        "1-3, the GA against random search on its budget): tasks.csv, tasks.md, tasks.png",
    )
    parser.add_argument(
        "--qd",
        action="store_true",
        help="run quality-diversity and co-design instead (4x4x3, 4x4x4, 3x3x6 x seeds 1-3: the "
        "GA, MAP-Elites on its budget, voxel-phase): qd.csv, qd.md, qd.png, qd_archives.png",
    )
    parser.add_argument(
        "--objectives",
        action="store_true",
        help="run several objectives and age protection instead (4x4x4 x seeds 1-3: NSGA-II, a "
        "weighted-sum GA with three weightings and random search, speed against cost of "
        "transport, on the same simulations; 4x4x3, 4x4x4, 3x3x6: AFPO against the GA on "
        "speed alone): tradeoff.csv, afpo.csv, objectives.md, fronts.png, hypervolume.png, "
        "afpo.png",
    )
    parser.add_argument(
        "--steady",
        action="store_true",
        help="run asynchronous steady-state evolution against the paper's GA instead (4x4x3, "
        "4x4x4, 3x3x6 x seeds 1-3, on the GA's simulations, each run alone for its wall time; "
        "and one run again with robots that take time in proportion to their size, compared "
        "with the instant one): steady.csv, timing.csv, steady.md, steady.png",
    )
    parser.add_argument(
        "--out",
        help="output folder, relative to the current folder (default docs/experiments; with "
        "--tasks docs/experiments/tasks, with --qd docs/experiments/qd, with --objectives "
        "docs/experiments/objectives, with --steady docs/experiments/steady: the repository's "
        "own when run from its root); the full path is printed first",
    )
    parser.add_argument(
        "--url", help="a running service (token from SOFTEVO_API_TOKEN); default: start one"
    )
    parser.add_argument(
        "--workers", type=int, help="pool processes of the private service (default: all cores)"
    )
    parser.add_argument(
        "--resume",
        action="store_true",
        help="reuse matching runs already in --out/softevo.db (or the --url service) instead of "
        "starting afresh; submit only the missing ones",
    )
    parser.set_defaults(handler=reproduce_command)


def reproduce_command(args: argparse.Namespace) -> int:
    """Everything it runs goes through the service (a private `softevo serve` or --url): its
    packages are checked first, then the suites are imported."""
    missing = need_service(("httpx",) if args.url else ("httpx", "fastapi", "uvicorn"))
    if missing:
        raise CommandError(f"it runs everything through the service: {missing}")
    from softevo.reproduce.command import reproduce

    return reproduce(args)
