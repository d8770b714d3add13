"""`softevo plot`: a run's learning curve, population dot plot and diversity chart as a PNG,
PDF or SVG (by the suffix of --out)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from softevo.command_error import CommandError
from softevo.core.outputs import figures
from softevo.results import read_results
from softevo.service_commands import need_service

KINDS = ("all", "curve", "population", "diversity")


def add_parser(commands: Any) -> None:
    plot = commands.add_parser(
        "plot",
        help="draw a run's curve, population dot plot and diversity chart (PNG, PDF or SVG)",
        description=(
            "Draw the paper's Figure 4(b)-(d) for one run: the learning curve, the population "
            "dot plot and the diversity chart, stacked in one figure (--kind picks one), written "
            "as PNG, PDF or SVG by the suffix of --out. RUN is a `softevo run` output folder, "
            "or a run id of the service at --url."
        ),
    )
    plot.add_argument("run", metavar="RUN_ID_OR_RESULTS_DIR")
    plot.add_argument(
        "--out",
        required=True,
        metavar="FIG.png",
        help="file to write; its suffix picks the format: .png, .pdf or .svg",
    )
    plot.add_argument("--kind", choices=KINDS, default="all", help="which figure (all)")
    plot.add_argument(
        "--url",
        default=os.environ.get("SOFTEVO_URL", "http://127.0.0.1:8000"),
        help="the service, for a run id (SOFTEVO_URL, default http://127.0.0.1:8000)",
    )
    plot.set_defaults(handler=plot_command)


def _from_service(url: str, run_id: int) -> tuple[dict[str, Any], list[Any], list[Any]]:
    """A run of the service at `url` (httpx, the service extra's: imported only for this)."""
    missing = need_service(("httpx",))
    if missing:
        raise CommandError(f"run {run_id} is read from the service: {missing}")
    import httpx

    try:
        return _read_run(url, run_id)
    except httpx.HTTPError as error:
        raise ValueError(f"cannot read run {run_id} from {url}: {error}") from None


def _read_run(url: str, run_id: int) -> tuple[dict[str, Any], list[Any], list[Any]]:
    import httpx

    token = os.environ.get("SOFTEVO_API_TOKEN")
    headers = {"Authorization": f"Bearer {token}"} if token else {}
    with httpx.Client(base_url=url, timeout=60, headers=headers) as client:
        run = client.get(f"/runs/{run_id}")
        if run.status_code == 404:
            raise ValueError(f"run {run_id} not found at {url}")
        run.raise_for_status()
        curve = client.get(f"/runs/{run_id}/curve").json()["generations"]
        items: list[Any] = []
        while True:
            page = client.get(
                f"/runs/{run_id}/individuals", params={"offset": len(items), "limit": 5000}
            ).json()
            items += page["items"]
            if not page["items"] or len(items) >= page["total"]:
                break
        return run.json()["config"], curve, items


def plot_command(args: argparse.Namespace) -> int:
    out = Path(args.out)
    try:
        figures.figure_format(out)
    except ValueError as error:
        args.parser.error(f"--out {error}")
    source = Path(args.run)
    try:
        if source.is_dir():
            config, curve, individuals = read_results(source)
        elif args.run.isdigit():
            config, curve, individuals = _from_service(args.url, int(args.run))
        else:
            raise ValueError(f"{args.run}: neither a results folder nor a run id")
    except ValueError as error:
        args.parser.exit(1, f"softevo plot: error: {error}\n")
    if not curve:
        args.parser.exit(1, f"softevo plot: error: {args.run} has no committed generation yet\n")
    title = figures.run_title(config)
    ylabel = figures.fitness_label(config)
    figure = {
        "all": lambda: figures.panel_figure(curve, individuals, title, ylabel),
        "curve": lambda: figures.curve_figure(curve, f"learning curve: {title}", ylabel),
        "population": lambda: figures.population_figure(
            individuals, f"population: {title}", ylabel
        ),
        "diversity": lambda: figures.diversity_figure(curve, f"diversity: {title}"),
    }[args.kind]()
    try:
        figures.save(figure, out)
    except OSError as error:
        args.parser.exit(1, f"softevo plot: error: cannot write {out}: {error.strerror}\n")
    print(f"wrote {out}")
    return 0
