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

from softevo.core.config import ConfigError, RunConfig, resolve
from softevo.core.objectives import OBJECTIVES
from softevo.core.search.generation import Step
from softevo.library import Result
from softevo.results import write_figures
from softevo.resume_checks import ResumeError
from softevo.run_arguments import CONFIG_FLAGS, DESCRIPTION, add_arguments, request_of
from softevo.run_config import breeding_notes, default_out

if TYPE_CHECKING:  # the store (SQLAlchemy) is imported by `softevo run` alone, when it runs
    from softevo.run_store import Checkpoints, Folder


def add_parser(commands: Any) -> None:
    run = commands.add_parser(
        "run",
        help="run a whole evolution experiment in this process",
        description=DESCRIPTION,
    )
    add_arguments(run)
    run.set_defaults(handler=run_command)


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
    if any(stored is not None and not _same_config(stored, config) for stored in found):
        args.parser.error(
            f"--out {out}: holds the results of another config; give another --out, "
            f"or --resume {out} to go on with that run"
        )


def _same_config(stored: object, config: RunConfig) -> bool:
    """Whether a stored config is `config`, read as this version reads it (a config stored
    before objectives had an ideal gains the default one, as the run itself would)."""
    if stored == config.to_json():
        return True
    if not isinstance(stored, dict):
        return False
    try:
        return resolve(stored).to_json() == config.to_json()
    except (ConfigError, TypeError, ValueError):
        return False


def _folder(args: argparse.Namespace) -> Folder:
    """The run to do and its folder: a new one, or (--resume) a stopped one."""
    parser: argparse.ArgumentParser = args.parser  # its error() exits
    from sqlalchemy.exc import SQLAlchemyError

    from softevo import run_store

    if args.resume is not None:
        given = [f"--{name}" for name in CONFIG_FLAGS if getattr(args, name) is not None]
        if args.out is not None:
            given.append("--out")
        if given:
            parser.error(f"--resume takes the run's own config; drop {', '.join(given)}")
        folder = Path(args.resume)
        try:
            if not folder.is_dir():
                raise ValueError(f"{folder}: not a resumable `softevo run` folder (not a folder)")
            return run_store.resume(_writable(args, folder), args.generations)
        except ResumeError as error:
            parser.error(f"--resume {folder}/{error}")
        except ValueError as error:
            parser.error(f"--resume {error}")
        except (OSError, SQLAlchemyError) as error:  # a full disk while importing a folder
            parser.error(f"--resume {folder}: cannot write its store ({_reason(error)})")
    try:
        config = resolve(request_of(args), new=True)
    except ConfigError as error:
        parser.error(str(error))
    for note in breeding_notes(config):
        print(f"softevo run: note: {note}", file=sys.stderr)
    out = Path(args.out) if args.out else default_out(config)
    _not_anothers(args, out, config)
    try:
        return run_store.new(_writable(args, out), config)
    except (ValueError, OSError, SQLAlchemyError) as error:
        parser.error(f"--out {out}: cannot start the run's store ({_reason(error)})")


def _reason(error: BaseException) -> str:
    from softevo.api.faults import reason

    return reason(error)


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
