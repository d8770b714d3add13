"""`softevo reproduce` itself: the paper's experiments or one suite, through the service's API
(imported when the command runs, so the parser needs nothing of the service)."""

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


def reproduce(args: argparse.Namespace) -> int:
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
            assert experiments.sweep_id is not None, "submit_all() submits the sweep"
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
