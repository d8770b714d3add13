"""`softevo run`: a whole evolution experiment in this process, with a live progress bar."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from softevo.core.config import PRESET_DESCRIPTIONS, PRESETS, ConfigError, RunConfig, resolve
from softevo.core.objectives import OBJECTIVES
from softevo.core.search.descriptors import CATALOGUE
from softevo.core.search.generation import Step
from softevo.library import Result
from softevo.results import write_figures
from softevo.resume_checks import ResumeError
from softevo.run_config import breeding_notes, default_out

if TYPE_CHECKING:  # the store (SQLAlchemy) is imported by `softevo run` alone, when it runs
    from softevo.run_store import Checkpoints, Folder

DESCRIPTION = (
    "Evolve robots in this process with a live progress bar. The output folder gets run.db, "
    "the run in the service's own store (SQLite, committed every generation: what --resume "
    "goes on from), and from it, after a generation once a second has passed since the last "
    "write and when the run ends or is stopped, "
    "config.json, curve.csv, curve.json, best_robot.json, state.json, cache.json and "
    "population.csv, and at the end curve.png, population.png and diversity.png; Ctrl-C "
    "stops, keeps them and draws the figures of the generations done. The default folder is "
    "named by the config (softevo-runs/PRESET-SHAPE-ALGORITHM-ENCODING-seedN-HASH, with the "
    "terrain, fitness and objectives where not the preset's; HASH: 8 hex digits of the "
    "whole config), and a folder holding another config's results is refused. --resume DIR "
    "goes on with a stopped run (Ctrl-C, a kill, a crash) to the same results an "
    "uninterrupted one gives, as the service takes a run over; run.db is checked against "
    "config.json first, and a folder of a release before run.db has its files checked "
    "against each other and the config, then imported (a folder edited or mixed with another "
    "run's files is refused in one line, nothing written). From Python: "
    "softevo.library.evolve (docs/python.md)."
)


def add_parser(commands: Any) -> None:
    run = commands.add_parser(
        "run",
        help="run a whole evolution experiment in this process",
        description=DESCRIPTION,
    )
    presets = "; ".join(f"{name}: {PRESET_DESCRIPTIONS[name]}" for name in sorted(PRESETS))
    run.add_argument("--preset", choices=sorted(PRESETS), help=f"(quick) {presets}")
    run.add_argument("--shape", metavar="NXxNYxNZ", help="bounding box, e.g. 5x5x3")
    run.add_argument(
<<<<<<< HEAD
        "--encoding",
        choices=["voxel", "voxel-phase", "cube-springs", "spring", "cppn"],
        help="voxel-phase: every actuated voxel evolves its own phase and amplitude (co-design); "
        "cppn: a network grows the body, phases and amplitudes (NEAT variation, docs/evolution.md)",
    )
=======
        "--encoding", metavar="NAME",
        help="voxel, voxel-phase, cube-springs, spring, cppn or one installed in the entry-point "
        "group softevo.encodings; voxel-phase: every actuated voxel evolves its own phase and "
        "amplitude (co-design); cppn: a network grows the body, phases and amplitudes (NEAT "
        "variation, docs/evolution.md)",
    )
>>>>>>> issue-50
    run.add_argument("--seed", type=int, help="random seed (0)")
    run.add_argument(
        "--population",
        type=int,
        metavar="P",
        help="robots per generation, each simulated once (default: the preset's, 16 for quick, "
        "25 for paper-voxel and the tasks)",
    )
    run.add_argument(
        "--generations", type=int, metavar="G", help="generations (with --resume: go on to G)"
    )
    run.add_argument("--duration", type=float, metavar="S", help="simulated seconds per robot")
    run.add_argument(
        "--objective",
        choices=list(OBJECTIVES),
        help="fitness: " + "; ".join(f"{k}: {v[0]} ({v[1]})" for k, v in OBJECTIVES.items()),
    )
    run.add_argument(
        "--terrain",
        type=terrain_json,
        metavar="JSON",
        help=f"the ground: {TERRAIN_EXAMPLES}; the task-* presets come with theirs",
    )
    _search_arguments(run)
    run.add_argument(
        "--workers", type=int, metavar="W", help="processes (default: one per core; 1 = serial)"
    )
    run.add_argument(
        "--out",
        metavar="DIR",
        help="output folder (softevo-runs/PRESET-SHAPE-ALGORITHM-ENCODING-seedN-HASH); one "
        "holding another config's results is refused",
    )
    run.add_argument(
        "--resume",
        metavar="DIR",
        help="go on with the stopped run in DIR (its run.db; a folder of a release before "
        "run.db is imported from its config.json, state.json and cache.json), writing there; "
        "only --generations, --workers and --json may be given with it",
    )
    run.add_argument("--json", action="store_true", help="print the result as JSON at the end")
    run.set_defaults(handler=run_command)


def _search_arguments(run: argparse.ArgumentParser) -> None:
    """The search strategy's flags: algorithm, its options, MAP-Elites' map, the objectives."""
    run.add_argument(
        "--algorithm",
        metavar="NAME",
        help="the search strategy: ga (the preset's), random or hillclimb (baselines), "
        "map-elites (quality-diversity over --descriptors, by default the map-elites "
        "preset's voxels,actuated x 8,8: writes archive.csv, archive.json and the archive.png "
        "heat map), nsga2 or afpo (several --objectives), steady-state (no generation "
        "barrier: births told in birth order, --options '{\"window\": W}'; W of 2-4 "
        "populations keeps the cores busy where children often repeat a parent), or any other "
        "installed one (softevo algorithms)",
    )
    run.add_argument(
        "--options",
        type=options_json,
        metavar="JSON",
        help="the strategy's own settings as a JSON object, e.g. '{\"keep\": 2}' "
        "(softevo algorithms lists each strategy's)",
    )
    run.add_argument(
        "--descriptors",
        type=_names,
        metavar="A,B",
        help="MAP-Elites descriptors, e.g. voxels,actuated or heading,voxels: "
        + "; ".join(f"{d.name} [{d.low:g}, {d.high:g}]: {d.help}" for d in CATALOGUE.values())
        + " (heading is measured by the simulation, the others read from the body)",
    )
    run.add_argument(
        "--bins",
        type=_counts,
        metavar="N,M",
        help="cells along each descriptor, e.g. 10,10 (default: 8 each)",
    )
    run.add_argument(
        "--objectives",
        type=_names,
        metavar="A,-B",
        help="several objectives at once, measures of the simulation (a leading - minimises), "
        "e.g. speed,-cost_of_transport, with --algorithm nsga2 or afpo: adds hypervolume and "
        "front_size to the curve, writes front.csv and front.png (docs/evolution.md)",
    )


def _request(args: argparse.Namespace) -> dict[str, Any]:
    request: dict[str, Any] = {"preset": args.preset or "quick", "seed": args.seed or 0}
    for name in (
        "shape",
        "encoding",
        "population",
        "generations",
        "algorithm",
        "options",
        "descriptors",
        "bins",
        "objectives",
    ):
        if getattr(args, name) is not None:
            request[name] = getattr(args, name)
    if args.objective is not None:
        request["objective"] = args.objective
    sim = {"duration": args.duration, "terrain": args.terrain}
    if any(value is not None for value in sim.values()):
        request["sim"] = {key: value for key, value in sim.items() if value is not None}
    return request


def _names(text: str) -> list[str]:
    return [part.strip() for part in text.split(",") if part.strip()]


def _counts(text: str) -> list[int]:
    try:
        return [int(part) for part in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected counts like 10,10, got {text!r}") from None


def options_json(text: str) -> dict[str, Any]:
    """`--options`: a JSON object (each strategy validates its own)."""
    return _json_object(text, 'expected an object like {"keep": 2}')


#: `--terrain`'s help: one example of each kind with sloping or raised ground.
TERRAIN_EXAMPLES = (
    """'{"kind": "slope", "angle_deg": 10}', '{"kind": "steps", "height": 0.2, "depth": 1}', """
    """'{"kind": "rough", "amplitude": 0.2, "wavelength": 3}', '{"kind": "hurdles", "height": """
    """0.15, "spacing": 2, "width": 0.5}' (a parameter left out takes its default: '{"kind": """
    """"rough"}' is a terrain; docs/tasks.md)"""
)


def terrain_json(text: str) -> dict[str, Any]:
    """`--terrain`: a JSON object (checked with the rest of the config)."""
    return _json_object(text, 'expected an object like {"kind": "flat"}')


def _json_object(text: str, expected: str) -> dict[str, Any]:
    try:
        value = json.loads(text)
    except json.JSONDecodeError as error:
        raise argparse.ArgumentTypeError(f"not JSON: {error.msg}") from None
    if not isinstance(value, dict):
        raise argparse.ArgumentTypeError(expected)
    return value


def _writable(args: argparse.Namespace, out: Path) -> Path:
    """`out`, made; an unwritable folder is refused before anything runs."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / ".write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as error:
        args.parser.error(f"--out {out}: cannot write ({error.strerror})")
    return out


def _not_anothers(args: argparse.Namespace, out: Path, config: RunConfig) -> None:
    """Refuse a folder that holds the results of a different config (the same config's are
    rewritten with the same numbers: a run is deterministic in its config)."""
    from softevo.run_store import config_json, stored_config

    # config.json, and the run in run.db (config.json may be gone)
    found = (config_json(out), stored_config(out))
    if any(stored is not None and stored != config.to_json() for stored in found):
        args.parser.error(
            f"--out {out}: holds the results of another config; give another --out, "
            f"or --resume {out} to go on with that run"
        )


def _folder(args: argparse.Namespace) -> Folder:
    """The run to do and its folder: a new one, or (--resume) a stopped one."""
    from sqlalchemy.exc import SQLAlchemyError

    from softevo import run_store

    if args.resume is not None:
        given = [f"--{name}" for name in _CONFIG_FLAGS if getattr(args, name) is not None]
        if args.out is not None:
            given.append("--out")
        if given:
            args.parser.error(f"--resume takes the run's own config; drop {', '.join(given)}")
        folder = Path(args.resume)
        try:
            if not folder.is_dir():
                raise ValueError(f"{folder}: not a resumable `softevo run` folder (not a folder)")
            return run_store.resume(_writable(args, folder), args.generations)
        except ResumeError as error:
            args.parser.error(f"--resume {folder}/{error}")
        except ValueError as error:
            args.parser.error(f"--resume {error}")
        except (OSError, SQLAlchemyError) as error:  # a full disk while importing a folder
            args.parser.error(f"--resume {folder}: cannot write its store ({_reason(error)})")
    try:
        config = resolve(_request(args))
    except ConfigError as error:
        args.parser.error(str(error))
    for note in breeding_notes(config):
        print(f"softevo run: note: {note}", file=sys.stderr)
    out = Path(args.out) if args.out else default_out(config)
    _not_anothers(args, out, config)
    try:
        return run_store.new(_writable(args, out), config)
    except (ValueError, OSError, SQLAlchemyError) as error:
        args.parser.error(f"--out {out}: cannot start the run's store ({_reason(error)})")


def _reason(error: BaseException) -> str:
    from softevo.api.faults import reason

    return reason(error)


_CONFIG_FLAGS = (
    "preset",
    "shape",
    "encoding",
    "seed",
    "population",
    "duration",
    "objective",
    "objectives",
    "terrain",
    "algorithm",
    "options",
    "descriptors",
    "bins",
)


def run_command(args: argparse.Namespace) -> int:
    if args.workers is not None and args.workers < 1:
        args.parser.error(f"--workers must be >= 1, got {args.workers}")
    folder = _folder(args)
    from sqlalchemy.exc import SQLAlchemyError

    from softevo.api.store.driving import GenerationMismatchError
    from softevo.run_store import TakenOverError

    out = folder.out
    try:
        return _run(args, folder)
    except (SQLAlchemyError, OSError) as error:  # a full disk, a folder gone read-only
        said = f"{out}/run.db: {_reason(error)}; what was committed is kept, go on with: "
        said += f"softevo run --resume {out}"
    except TakenOverError:  # a second `softevo run --resume` on the folder: it goes on
        said = f"{out}: another softevo run took this run over and goes on with it"
    except GenerationMismatchError as error:  # a store edited by hand
        said = f"{out}/run.db: {error}"
    finally:
        folder.close()
    print(f"softevo run: error: {said}", file=sys.stderr)
    return 1


def _run(args: argparse.Namespace, folder: Folder) -> int:
    out, config = folder.out, folder.config
    resumed_to = args.generations if args.resume else None
    generations = config.generations if resumed_to is None else resumed_to
    from softevo.run_store import Checkpoints

    checkpoints = Checkpoints(folder)
    try:
        with Progress(*_columns(config), console=Console(stderr=True), transient=args.json) as bar:
            _drive(folder, args.workers, generations, checkpoints, bar)
    except KeyboardInterrupt:
        evolution = checkpoints.flush()
        done = len(evolution.state.history)
        if done:
            write_figures(out, evolution)
        print(
            f"interrupted after {done} of {generations} generations; "
            f"partial results{' and figures' if done else ''} in {out}/; "
            f"go on with: softevo run --resume {out}",
            file=sys.stderr,
        )
        return 130
    evolution = checkpoints.flush()
    write_figures(out, evolution)
    _print_summary(args, Result.of(evolution), out)
    return 0


def _columns(config: RunConfig) -> tuple[Any, ...]:
    return (
        TextColumn("generation"),
        MofNCompleteColumn(),
        BarColumn(),
        TextColumn(
            f"best {{task.fields[best]}} {OBJECTIVES[config.objective][1]}"
            "  {task.fields[rate]} eval/s"
        ),
        TimeRemainingColumn(),
    )


def _drive(
    folder: Folder, workers: int | None, generations: int, checkpoints: Checkpoints, bar: Progress
) -> None:
    """The run to its end through the store, the bar and the files following each generation."""
    from softevo import run_store

    done, evaluations, _, elapsed = folder.totals()
    task = bar.add_task("run", total=generations, completed=done, best="-", rate="-")
    counted = {"evaluations": evaluations, "elapsed": elapsed}

    def report(step: Step) -> None:
        checkpoints.done()
        counted["evaluations"] += step.stats.evaluations
        counted["elapsed"] += step.seconds
        rate = counted["evaluations"] / counted["elapsed"] if counted["elapsed"] > 0 else math.nan
        bar.update(
            task,
            completed=step.stats.generation + 1,
            best=f"{step.stats.best_so_far:.4f}",
            rate=f"{rate:.1f}",
        )

    run_store.drive(folder, workers, generations, report)


def _value(fitness: float | None) -> str:
    return "-" if fitness is None else f"{fitness:.4f}"  # every robot failed: no best


def _print_summary(args: argparse.Namespace, result: Result, out: Path) -> None:
    config = result.config
    if args.json:
        print(json.dumps({**result.to_json(), "out": str(out)}, allow_nan=False))
    else:
        print(
            f"{config['generations']} generations of {config['population']} "
            f"({config['encoding']}, {'x'.join(map(str, config['shape']))}, "
            f"seed {config['seed']}): best {_value(result.best_fitness)} "
            f"{OBJECTIVES[config['objective']][1]} "
            f"(generation {result.best_generation}), "
            f"{result.evaluations} simulations, {result.saved} saved by the cache, "
            f"{result.wall_seconds:.1f} s\nresults in {out}/",
            file=sys.stdout,
        )
