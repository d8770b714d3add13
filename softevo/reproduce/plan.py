"""What `softevo reproduce` runs: the paper's boxes, the experiments past it, and the full and
quick plans (the same code path, tiny settings)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from softevo.core.status import FINAL as FINAL_STATUSES

PAPER_NINE = [
    (3, 3, 6),
    (4, 4, 3),
    (4, 4, 4),
    (5, 5, 3),
    (5, 5, 4),
    (5, 5, 5),
    (6, 6, 3),
    (6, 6, 6),
    (9, 9, 2),
]
FINAL = {str(status) for status in FINAL_STATUSES}
#: 2 pi rad/s: one actuation period a second, 9 in paper-voxel's clock (1.4 at the paper's 1 rad/s)
FAST_OMEGA = 2 * math.pi
CLOCK = ("clock", "omega 2pi")  # the boxes' sweep again at FAST_OMEGA
GA_ON_FOCUS = ("ablation", "paper settings")  # the GA at the paper's settings on the focus box
REFERENCES = {"paper settings", "GA (paper-voxel)"}  # the GA rows others are compared with


@dataclass(frozen=True)
class Plan:
    """What to run: the full reproduction, or a tiny one with the same code path (`--quick`)."""

    boxes: list[tuple[int, int, int]]
    seeds: list[int]
    voxel: dict[str, Any]  # the paper-voxel request every voxel experiment starts from
    cube: dict[str, Any]  # the phase 2 request
    focus: tuple[int, int, int]  # the box of the baselines and the ablation
    encoding_boxes: list[tuple[int, int, int]]
    ablation: dict[str, dict[str, Any]]
    climbers: int = 5  # hill climber population: the best and 4 mutants per generation
    # more seeds on the focus box (GA, baselines, ablation): its comparisons are the noisiest
    extra_focus_seeds: list[int] = field(default_factory=list)
    # the boxes again with a faster actuation, so the fitness clock spans many periods
    clock_sim: dict[str, Any] = field(default_factory=lambda: {"omega": FAST_OMEGA})

    @property
    def focus_seeds(self) -> list[int]:
        return self.seeds + [s for s in self.extra_focus_seeds if s not in self.seeds]


FULL = Plan(
    boxes=PAPER_NINE,
    seeds=[1, 2, 3],
    voxel={"preset": "paper-voxel"},
    cube={"preset": "paper-cube"},
    focus=(4, 4, 4),
    encoding_boxes=PAPER_NINE,
    ablation={
        "tournament selection": {"selection": "tournament"},
        "mutation 0.5": {"mutation_probability": 0.5},
        "no immigrants": {"immigrants": 0.0},
    },
    extra_focus_seeds=[4, 5],
)
QUICK = Plan(
    boxes=[(2, 2, 2), (3, 2, 2)],
    seeds=[1, 2],
    voxel={
        "preset": "paper-voxel",
        "population": 6,
        "generations": 3,
        "sim": {"duration": 1.0, "settle_time": 0.3},
    },
    cube={
        "preset": "paper-cube",
        "population": 6,
        "generations": 3,
        "sim": {"duration": 1.0, "settle_time": 0.3},
    },
    focus=(2, 2, 2),
    encoding_boxes=[(2, 2, 2)],
    ablation={"mutation 0.5": {"mutation_probability": 0.5}},
    climbers=3,
    extra_focus_seeds=[3],
)
