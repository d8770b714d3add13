"""`softevo algorithms`: the installed search strategies, with the settings each one reads."""

from __future__ import annotations

import argparse
import json
from typing import Any

from softevo.core.search.configured import describe_strategies
from softevo.core.search.registry import GROUP


def add_parser(commands: Any) -> None:
    parser = commands.add_parser(
        "algorithms",
        help="list the installed search strategies and their settings",
        description=(
            f"List the search strategies installed in the entry-point group {GROUP} (the "
            "built-ins and any a package adds), each with the run settings it reads and its "
            'own options (given as --options JSON to softevo run, or "options" in POST '
            "/runs). docs/evolution.md shows how to write one."
        ),
    )
    parser.add_argument("--json", action="store_true", help="print them as JSON")
    parser.set_defaults(handler=algorithms_command)


def algorithms_command(args: argparse.Namespace) -> int:
    described = describe_strategies()
    if args.json:
        print(json.dumps(described, indent=2))
        return 0
    for entry in described:
        print(f"{entry['name']}: {entry['summary']}")
        print(f"  settings: {', '.join(item['name'] for item in entry['uses'])}")
        options = entry["options"].get("properties", {})
        for name, schema in options.items():
            default = f" (default {schema['default']})" if "default" in schema else ""
            print(f"  option {name}{default}: {schema.get('description', '')}")
    return 0
