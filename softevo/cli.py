"""The `softevo` command. The physics (numba) is imported only by the commands that simulate,
when they run: `--help`, `serve` with Redis, `plot` and `db` never load it
(tests/test_imports.py checks that in a fresh interpreter).

Exit codes: 0 success, 1 bad input (one line on stderr naming the problem), 2 bad usage, 130
interrupted (Ctrl-C), 141 stdout closed by its reader (`| head`; quietly, no traceback).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NoReturn

from softevo import (
    __version__,
    algorithms_command,
    docs_command,
    plot_command,
    reproduce,
    run_command,
    service_commands,
)
from softevo.command_error import CommandError
from softevo.core.outputs.export import FORMATS


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text!r}")
    return value


def _cmd_simulate(args: argparse.Namespace) -> int:
    from softevo import library
    from softevo.core.robots.robot_file import RobotFileError

    fps = args.fps if args.trajectory else None
    if args.trajectory:
        _check_out(args.trajectory)
    try:
        measures = library.simulate(
            args.robot, duration=args.duration, terrain=args.terrain, trajectory_fps=fps
        )
    except RobotFileError as error:
        raise CommandError(str(error)) from None
    if measures["dropped_voxels"]:
        print(
            f"softevo simulate: {args.robot}: {measures['dropped_voxels']} filled voxel(s) not "
            "face-connected to the largest group were dropped (not simulated)",
            file=sys.stderr,
        )
    trajectory = measures.pop("trajectory", None)
    if trajectory is not None:
        try:
            Path(args.trajectory).write_text(json.dumps(trajectory) + "\n")
        except OSError as error:
            raise CommandError(f"{args.trajectory}: cannot write ({error.strerror})") from None
    print(json.dumps(measures, indent=2, allow_nan=False))
    if not measures["stable"]:  # the measures are null: say why, in one line
        raise CommandError(
            f"{args.robot}: the simulation blew up (positions not finite, or a spring stretched "
            "past its limit), so every measure is null; try a smaller sim.dt"
        )
    return 0


def _check_out(path: str) -> None:
    """Say that `path` cannot be written before simulating or drawing anything, not after."""
    out = Path(path)
    folder = out.parent
    if out.is_dir():
        reason = "a folder"
    elif not folder.is_dir():
        reason = f"no folder {folder}" if not folder.exists() else f"{folder} is not a folder"
    elif not os.access(folder, os.W_OK | os.X_OK):
        reason = f"folder {folder} is not writable"
    else:
        return
    raise CommandError(f"{path}: cannot write ({reason})")


def _not_a_folder(args: argparse.Namespace, example: str, formats: str) -> None:
    """--out naming a folder: say so and what it takes (a file, its suffix the format)."""
    if Path(args.out).is_dir():
        args.parser.error(
            f"--out {args.out} is a folder: give the file to write, e.g. "
            f"{Path(args.out) / example} (its suffix names the format: {formats})"
        )


def _write_file(path: str, data: bytes, format: str) -> int:
    """Write an exported or rendered file and say so on stderr (stdout stays free)."""
    try:
        Path(path).write_bytes(data)
    except OSError as error:
        raise CommandError(f"{path}: cannot write ({error.strerror})") from None
    print(f"{path}: {format}, {len(data)} bytes", file=sys.stderr)
    return 0


def _cmd_export(args: argparse.Namespace) -> int:
    from softevo.core.outputs.export import ExportError, export_robot, format_from_path
    from softevo.core.robots.robot_file import RobotFileError, load_robot

    _not_a_folder(args, "robot.glb", ", ".join(f".{name}" for name in FORMATS))
    named = format_from_path(args.out)
    if args.format and named and args.format != named:
        args.parser.error(f"--format {args.format} but --out {args.out!r} names {named}: say one")
    format = args.format or named
    if format is None:
        args.parser.error(
            f"--format is needed: the suffix of {args.out!r} names no format ({', '.join(FORMATS)})"
        )
    _check_out(args.out)
    try:
        robot = load_robot(args.robot)
    except RobotFileError as error:
        raise CommandError(f"{args.robot}: {error}") from None
    try:
        data = export_robot(robot, format)
    except ExportError as error:
        raise CommandError(f"{args.robot}: {error}") from None
    return _write_file(args.out, data, format)


def _add_export(commands: Any) -> None:
    export = commands.add_parser(
        "export",
        help="write a robot file as a Voxelyze .vxa, a glTF .glb or an STL mesh",
        description=(
            "Write ROBOT.json (format softevo.robot/1) for other tools (docs/export.md): vxa is "
            "the XML of Voxelyze, VoxCAD and voxcraft-sim (materials with the Young's modulus "
            "of a solid of softevo voxels, Elastic_Mod = 7.58 x stiffness / edge_length, "
            "actuation per voxel with TempPeriod = 2 pi / omega; voxel robots only, co-designed "
            "ones too; evosoro's Voxelyze runs it as it is and writes softevo_fitness.xml); glb "
            "(glTF 2.0 binary, coloured by material, +Y up) and stl are the voxel surface in "
            "metres. Exits 1 if the file is invalid or cannot be written in that format."
        ),
    )
    export.add_argument(
        "robot",
        metavar="ROBOT.json",
        help="robot file, or a `softevo run` results folder (its best_robot.json)",
    )
    export.add_argument(
        "--format",
        choices=FORMATS,
        help="file format (default: from the suffix of --out)",
    )
    export.add_argument("--out", required=True, metavar="FILE", help="file to write")
    export.set_defaults(handler=_cmd_export)


def _cmd_replay(args: argparse.Namespace) -> int:
    from softevo.core.outputs import picture
    from softevo.core.robots.robot_file import RobotFileError, load_robot

    _not_a_folder(args, "robot.gif", ".gif or .mp4")
    format = Path(args.out).suffix.lower().lstrip(".")
    if format not in picture.PICTURE_FORMATS:
        args.parser.error(f"--out must end in .gif or .mp4, got {args.out!r}")
    if format == "mp4" and not picture.ffmpeg_available():
        raise CommandError(picture.FFMPEG_MISSING)  # not the robot's fault: said before reading it
    _check_picture_options(args)
    _check_out(args.out)
    try:
        robot = load_robot(args.robot)
    except RobotFileError as error:
        raise CommandError(f"{args.robot}: {error}") from None
    try:
        seconds = args.duration if args.duration is not None else picture.one_period(robot)
        data = picture.movie(robot, format, args.fps, seconds)
    except picture.PictureError as error:
        raise CommandError(f"{args.robot}: {error}") from None
    return _write_file(args.out, data, format)


def _check_picture_options(args: argparse.Namespace) -> None:
    """--fps and --duration out of range: a usage error naming the option, before the robot is
    read (argparse has already refused values that are not finite numbers > 0)."""
    from softevo.core.limits import MAX_PICTURE_FPS, MAX_PICTURE_SECONDS, MIN_PICTURE_FPS

    if not MIN_PICTURE_FPS <= args.fps <= MAX_PICTURE_FPS:
        args.parser.error(
            f"--fps must be between {MIN_PICTURE_FPS:g} and {MAX_PICTURE_FPS:g} frames per "
            f"simulated second, got {args.fps:g}"
        )
    if args.duration is not None and args.duration > MAX_PICTURE_SECONDS:
        args.parser.error(
            f"--duration must be at most {MAX_PICTURE_SECONDS:g} simulated seconds, "
            f"got {args.duration:g}"
        )


def _add_replay(commands: Any) -> None:
    from softevo.core.limits import MAX_PICTURE_FPS, MAX_PICTURE_SECONDS, MIN_PICTURE_FPS

    replay = commands.add_parser(
        "replay",
        help="render a robot's simulation as a GIF or MP4",
        description=(
            "Simulate ROBOT.json and draw it offscreen as shaded voxels that deform with the "
            "masses, coloured by material, on its ground, the camera following the centre of "
            'mass, a clock on every frame (README "Moving pictures"). .gif needs nothing '
            "more; .mp4 needs the ffmpeg program on PATH. Exits 1 if the file is invalid."
        ),
    )
    replay.add_argument(
        "robot",
        metavar="ROBOT.json",
        help="robot file, or a `softevo run` results folder (its best_robot.json)",
    )
    replay.add_argument("--out", required=True, metavar="FILE.gif|FILE.mp4", help="file to write")
    replay.add_argument(
        "--fps",
        type=_positive_float,
        default=12.0,
        help=f"frames per simulated second (12; {MIN_PICTURE_FPS:g} to {MAX_PICTURE_FPS:g})",
    )
    replay.add_argument(
        "--duration",
        type=_positive_float,
        metavar="S",
        help="simulated seconds drawn (default: one actuation period, 2 pi / omega: 6.28 s at "
        f"the paper's 1 rad/s; at least 3, at most {MAX_PICTURE_SECONDS:g})",
    )
    replay.set_defaults(handler=_cmd_replay)


class Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (the full usage is in --help), exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="softevo",
        description="Evolve modular soft crawling robots. The guides that help texts name as "
        "docs/NAME.md are installed with softevo: `softevo docs NAME` prints one.",
    )
    parser.add_argument("--version", action="version", version=f"softevo {__version__}")
    commands = parser.add_subparsers(
        dest="command", required=True, metavar="COMMAND", parser_class=Parser
    )
    run_command.add_parser(commands)
    algorithms_command.add_parser(commands)
    reproduce.add_parser(commands)
    plot_command.add_parser(commands)
    service_commands.add_parsers(commands)
    docs_command.add_parser(commands)

    simulate = commands.add_parser(
        "simulate",
        help="simulate one robot file and print its result as JSON",
        description=(
            "Simulate ROBOT.json (format softevo.robot/1) and print one JSON object: masses, "
            "springs, steps, com_start, com_end, distance (m), speed (m/s), forward_speed "
            "(m/s along +x), climb_rate (m/s), energy (J of actuator work), cost_of_transport "
            "(energy / (mass x g x distance)), wall_seconds, stable, dropped_voxels (filled "
            "voxels not face-connected to the largest group, which are not built; also said "
            "on stderr); all measured from sim.settle_time on. Exits 1 if the file is invalid "
            "or the simulation blew up. From Python: softevo.library.simulate (docs/python.md)."
        ),
    )
    simulate.add_argument(
        "robot",
        metavar="ROBOT.json",
        help="robot file, or a `softevo run` results folder (its best_robot.json)",
    )
    simulate.add_argument(
        "--duration", type=_positive_float, metavar="S", help="simulated seconds (overrides sim)"
    )
    simulate.add_argument(
        "--terrain",
        type=run_command.terrain_json,
        metavar="JSON",
        help=f"simulate on this ground instead: {run_command.TERRAIN_EXAMPLES}",
    )
    simulate.add_argument(
        "--trajectory", metavar="OUT.json", help="also write mass positions over time to this file"
    )
    simulate.add_argument(
        "--fps", type=_positive_float, default=30.0, help="trajectory frames per second (30)"
    )
    simulate.set_defaults(handler=_cmd_simulate)
    _add_export(commands)
    _add_replay(commands)
    for subparser in commands.choices.values():
        subparser.set_defaults(parser=subparser)
    return parser


def _quiet_broken_pipe() -> int:
    """stdout was closed by the reader (`softevo simulate ... | head`): stop without a
    traceback, and keep Python's flush at exit from raising again. 141 = 128 + SIGPIPE."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    with contextlib.suppress(OSError, ValueError):  # a stdout without a descriptor (tests)
        os.dup2(devnull, sys.stdout.fileno())
    return 141


def main(argv: Sequence[str] | None = None) -> int:
    try:
        return _main(argv)
    except BrokenPipeError:
        return _quiet_broken_pipe()


def _main(argv: Sequence[str] | None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    handler: Callable[[argparse.Namespace], int] = args.handler
    try:
        return handler(args)
    except CommandError as error:
        print(f"softevo {args.command}: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"softevo {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
