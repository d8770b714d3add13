"""Draw docs/img/terrains.png: the task presets' terrains in side view (y = 0), with the 4x4x4
robot's starting footprint. `python scripts/draw_terrains.py`."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from softevo.core.outputs import figures
from softevo.core.robots.settings import sim_settings
from softevo.core.robots.tasks import TASKS


def main() -> None:
    plt = figures.pyplot()
    figure, axes = plt.subplots(len(TASKS), 1, figsize=(7.0, 1.3 * len(TASKS)), sharex=True)
    x = np.linspace(-2.0, 14.0, 3201)
    for ax, (name, (_asks, terrain, objective)) in zip(axes, TASKS.items(), strict=True):
        surface = sim_settings({"terrain": terrain}).terrain.surface(x, np.zeros_like(x))
        ax.fill_between(x, surface, surface.min() - 0.3, color="#8fa3b5")
        ax.add_patch(
            plt.Rectangle(
                (0, surface[(x >= 0) & (x <= 4)].max()), 4, 4, fill=False, ls="--", color="#d1495b"
            )
        )
        ax.set_title(f"{name} ({objective})", fontsize=9, loc="left")
        ax.set_ylim(surface.min() - 0.3, max(4.5, surface.max() + 0.5))
        ax.set_ylabel("z (m)", fontsize=8)
    axes[-1].set_xlabel("x (m); dashed: the 4x4x4 box a robot starts in")
    figure.tight_layout()
    figures.save(figure, Path(__file__).resolve().parents[1] / "docs" / "img" / "terrains.png")


if __name__ == "__main__":
    main()
