"""What `softevo run` accepts: its flags, their parsing, and the request they make."""

from __future__ import annotations

import argparse
import json
from typing import Any

from softevo.core.config import PRESET_DESCRIPTIONS, PRESETS
from softevo.core.objectives import OBJECTIVES
from softevo.core.search.descriptors import CATALOGUE

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


def add_arguments(run: argparse.ArgumentParser) -> None:
    """Every flag of `softevo run`."""
    presets = "; ".join(f"{name}: {PRESET_DESCRIPTIONS[name]}" for name in sorted(PRESETS))
    run.add_argument("--preset", choices=sorted(PRESETS), help=f"(quick) {presets}")
    run.add_argument("--shape", metavar="NXxNYxNZ", help="bounding box, e.g. 5x5x3")
    run.add_argument(
        "--encoding",
        metavar="NAME",
        help="voxel, voxel-phase, cube-springs, spring, cppn or one installed in the entry-point "
        "group softevo.encodings; voxel-phase: every actuated voxel evolves its own phase and "
        "amplitude (co-design); cppn: a network grows the body, phases and amplitudes (NEAT "
        "variation, docs/evolution.md)",
    )
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
    run.add_argument(
        "--max-simulations",
        type=int,
        metavar="N",
        dest="max_simulations",
        help="a budget in simulations: the run ends at the first generation (or steady-state "
        "row) whose simulations so far reach N, or at --generations, whichever comes first",
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
    _output_arguments(run)


def _output_arguments(run: argparse.ArgumentParser) -> None:
    """Where the run goes and how it runs."""
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
        "e.g. speed,-cost_of_transport, with --algorithm nsga2 or afpo: adds hypervolume, "
        "front_size and normalised_hypervolume (0-1) to the curve, writes front.csv and "
        "front.png (docs/evolution.md)",
    )


def request_of(args: argparse.Namespace) -> dict[str, Any]:
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
        "max_simulations",
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


CONFIG_FLAGS = (
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
    "max_simulations",
)
