"""What `softevo run` makes of a resolved config before it runs: the name of its default folder,
and the one-line notes on settings its algorithm does not breed on.

A folder name says what ran (preset, box, algorithm, encoding, and the terrain, fitness and
objectives where they are not the preset's) so a folder of runs reads without opening each
config.json; the hash of the whole config still keeps two configs out of one folder.
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

from softevo.core.config import PRESETS, RunConfig
from softevo.core.search.registry import strategy_class

#: Characters a folder name keeps; any other (in a plugin's algorithm name) becomes "_".
_UNSAFE = re.compile(r"[^A-Za-z0-9._+-]")
#: The longest label before the seed and hash (a file name may have 255 bytes).
MAX_LABEL = 160


def config_hash(config: RunConfig) -> str:
    """8 hex digits of the whole resolved config: two configs never share a default folder."""
    text = json.dumps(config.to_json(), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:8]


def _preset_default(config: RunConfig) -> tuple[str, str]:
    """The terrain kind and fitness the config's preset comes with."""
    preset = PRESETS.get(config.preset or "", {})
    terrain = preset.get("sim", {}).get("terrain", {}).get("kind", "flat")
    return terrain, preset.get("objective", "speed")


def folder_label(config: RunConfig) -> str:
    """quick-3x3x3-nsga2-voxel-speed+min_cost_of_transport: what ran, in a file name's letters."""
    parts = [
        config.preset or "custom",
        "x".join(map(str, config.shape)),
        config.algorithm,
        config.encoding,
    ]
    terrain, objective = _preset_default(config)
    if config.sim.terrain.kind != terrain:
        parts.append(config.sim.terrain.kind)
    if config.objective != objective:
        parts.append(config.objective)
    if config.objectives:
        names = (
            f"{'min_' if spec.goal == 'min' else ''}{spec.measure}" for spec in config.objectives
        )
        parts.append("+".join(names))
    return _UNSAFE.sub("_", "-".join(parts))[:MAX_LABEL]


def default_out(config: RunConfig) -> Path:
    """softevo-runs/quick-3x3x3-ga-voxel-seed0-1a2b3c4d (LABEL-seedN-HASH)."""
    name = f"{folder_label(config)}-seed{config.seed}-{config_hash(config)}"
    return Path("softevo-runs") / name


def breeding_notes(config: RunConfig) -> list[str]:
    """One line for each of objectives and descriptors that the algorithm does not breed on:
    they are not ignored (any run keeps the front and the archive beside its search, which is
    how random search or the GA is compared on them) but they do not steer it."""
    found = strategy_class(config.algorithm)
    notes = []
    if config.objectives and not found.breeds_on(config, "objectives"):
        notes.append(
            f"{config.algorithm} selects on the fitness ({config.objective}) alone, not on "
            "--objectives: their front is only kept beside it (front.csv, front.png, curve.csv "
            "hypervolume); nsga2 and afpo select on them, as does ga with --options "
            "'{\"weights\": [...]}'"
        )
    if config.descriptors and not found.breeds_on(config, "descriptors"):
        notes.append(
            f"{config.algorithm} does not breed from the archive over the descriptors: it is only "
            "kept beside it, for comparison (archive.csv, archive.png); map-elites breeds from it"
        )
    return notes
