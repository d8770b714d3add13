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
import math
import os
import time
from pathlib import Path
from typing import Any

from softevo.client import APIError, UnreachableError
from softevo.reproduce.champions import breathing_cube, champions, champions_table
from softevo.reproduce.client import service
from softevo.reproduce.experiments import Experiments, wall_seconds
from softevo.reproduce.figures import write_figures
from softevo.reproduce.objectives import run_objectives
from softevo.reproduce.objectives_report import write_objectives
from softevo.reproduce.plan import FULL, QUICK
from softevo.reproduce.qd import run_qd, write_qd
from softevo.reproduce.steady import RUNNING, run_steady
from softevo.reproduce.steady_report import write_steady
from softevo.reproduce.tables import fmt, write_tables
from softevo.reproduce.tasks import run_suite, write_suite


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
        "--tasks", action="store_true",
        help="run the task suite instead (task-flat, -slope, -stairs, -rough, -hurdles x seeds "
        "1-3, the GA against random search on its budget): tasks.csv, tasks.md, tasks.png",
    )  # fmt: skip
    parser.add_argument(
        "--qd", action="store_true",
        help="run quality-diversity and co-design instead (4x4x3, 4x4x4, 3x3x6 x seeds 1-3: the "
        "GA, MAP-Elites on its budget, voxel-phase): qd.csv, qd.md, qd.png, qd_archives.png",
    )  # fmt: skip
    parser.add_argument(
        "--objectives", action="store_true",
        help="run several objectives and age protection instead (4x4x4 x seeds 1-3: NSGA-II, a "
        "weighted-sum GA with three weightings and random search, speed against cost of "
        "transport, on the same simulations; 4x4x3, 4x4x4, 3x3x6: AFPO against the GA on "
        "speed alone): tradeoff.csv, afpo.csv, objectives.md, fronts.png, hypervolume.png, "
        "afpo.png",
    )  # fmt: skip
    parser.add_argument(
        "--steady", action="store_true",
        help="run asynchronous steady-state evolution against the paper's GA instead (4x4x3, "
        "4x4x4, 3x3x6 x seeds 1-3, on the GA's simulations, each run alone for its wall time; "
        "and one run again with robots that take time in proportion to their size, compared "
        "with the instant one): steady.csv, timing.csv, steady.md, steady.png",
    )  # fmt: skip
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
    plan = QUICK if args.quick else FULL
    chosen = [name for name in ("tasks", "qd", "objectives", "steady") if getattr(args, name)]
    if len(chosen) > 1:
        args.parser.error(f"--{' and --'.join(chosen)} are {len(chosen)} suites: run one at a time")
    suite = chosen[0] if chosen else None
    out = Path(args.out or (f"docs/experiments/{suite}" if suite else "docs/experiments"))
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / ".write-test").touch()
        (out / ".write-test").unlink()
    except OSError as error:
        args.parser.error(f"--out {out.absolute()}: cannot write there ({error.strerror})")
    started = time.monotonic()
    flags = " --quick" if args.quick else ""
    if suite is not None:
        return _suite(args, out, started, suite)
    print(f"softevo reproduce{flags}: results in {out.absolute()}/", flush=True)
    phase1 = breathing_cube(out, args.quick)
    try:
        with service(args.url, out, args.workers, args.resume) as client:
            experiments = Experiments(client, plan, resume=args.resume)
            experiments.submit_all()
            experiments.wait()
            figure4 = write_figures(experiments, out)
            sweep = client.get_sweep(experiments.sweep_id).status()
            rows = experiments.rows()
            longer = champions(experiments, out)
    except APIError as error:
        raise SystemExit(f"softevo reproduce: {error}") from None
    except UnreachableError as error:
        where = args.url or "the private service"
        raise SystemExit(f"softevo reproduce: error: {where}: {error}") from None
    wall = time.monotonic() - started
    notes = _notes(args, out, experiments, phase1, figure4, sweep, wall)
    write_tables(rows, out, notes, champions_table(longer))
    print(f"done in {wall:.0f} s: {out / 'results.md'}")
    return 0


def _suite(args: argparse.Namespace, out: Path, started: float, suite: str) -> int:
    """`--tasks`, `--qd`, `--objectives` or `--steady`: one suite through the service, its
    tables and figures."""
    flags = " --quick" if args.quick else ""
    command = f"softevo reproduce --{suite}{flags} --out {out}" + (
        f" --url {args.url}" if args.url else ""
    )
    print(f"{command}: results in {out.absolute()}/", flush=True)
    try:
        running = RUNNING if suite == "steady" else 2
        with service(args.url, out, args.workers, args.resume, running) as client:
            if suite == "qd":
                rows, archives = run_qd(client, args.quick)
            elif suite == "objectives":
                results = run_objectives(client, args.quick)
            elif suite == "steady":
                steady = run_steady(client, args.quick, args.workers)
            else:
                rows = run_suite(client, args.quick)
    except APIError as error:
        raise SystemExit(f"softevo reproduce: {error}") from None
    except UnreachableError as error:
        where = args.url or "the private service"
        raise SystemExit(f"softevo reproduce: error: {where}: {error}") from None
    wall = time.monotonic() - started
    if suite == "qd":
        write_qd(rows, archives, out, command, wall)
    elif suite == "objectives":
        write_objectives(results, out, command, wall)
    elif suite == "steady":
        write_steady(steady, out, command, wall)
    else:
        write_suite(rows, out, command, wall)
    print(f"done in {wall:.0f} s: {out / f'{suite}.md'}")
    return 0


def _notes(
    args: argparse.Namespace,
    out: Path,
    experiments: Experiments,
    phase1: dict[str, Any],
    figure4: dict[str, Any],
    sweep: dict[str, Any],
    wall: float,
) -> list[str]:
    """The paragraphs under the tables: the command, the time, how to read the budgets."""
    flags = " --quick" if args.quick else ""
    runs = list({r["id"]: r for g in experiments.groups for r in g.runs}.values())
    walls = [w for w in (wall_seconds(r) for r in runs) if math.isfinite(w)]
    reused = (
        f" ({experiments.reused} of them reused from an earlier invocation by --resume)"
        if experiments.reused
        else ""
    )
    notes = [
        f"Command: `softevo reproduce{flags} --out {out}"
        + (f" --url {args.url}" if args.url else "")
        + f"`; {len(runs)} runs through the REST API{reused}, sweep {experiments.sweep_id} "
        f"holds the boxes and sweep {experiments.clock_sweep_id} the boxes at 2 pi rad/s; this "
        f"machine has {os.cpu_count()} cores.",
        f"Wall time: {experiments.busy():.0f} s with at least one run going (the union of the "
        f"runs' start-to-finish intervals, from the API); the runs' own wall times add up to "
        f"{sum(walls):.0f} s"
        + (
            "."
            if args.url
            else ", because the private service ran two at a time (SOFTEVO_MAX_RUNNING=2) on "
            "one pool of processes, so a run's wall time is about twice what it would be alone."
        )
        + f" This invocation took {wall:.0f} s.",
        "Simulations: a run's simulations (its evaluations) are the genomes it simulated; the "
        "rest of its population came from its fitness cache (survivors, repeats). The "
        "baselines were given the paper-voxel GA's mean simulations on their box; 'best within "
        "the GA's simulations' is each run's best so far at the last generation that stayed "
        "within that many, so variants that simulate more are compared on equal terms.",
        f"Phase 1 (breathing cube, simulated in process with core.physics for "
        f"{phase1['duration']:.0f} s): speed {fmt(phase1['speed'], 5)} m/s, net distance "
        f"{fmt(phase1['distance'], 5)} m, final centre-of-mass height "
        f"{phase1['final_height']:.4f} m, stable {phase1['stable']}.",
        f"Figure 4(b)-(d): run {figure4['figure4_run']} (box "
        f"{'x'.join(map(str, figure4['figure4_box']))}, seed {figure4['figure4_seed']}).",
        "Sweep as the API reports it (best mean per box): "
        + ", ".join(
            f"{'x'.join(map(str, b['shape']))} {fmt(b['best_mean'])}" for b in sweep["boxes"]
        )
        + ".",
    ]
    return notes
