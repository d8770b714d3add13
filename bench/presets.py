"""Do the paper's phase 3 numbers evolve well? `python bench/presets.py` (about 2 minutes).

Runs `paper-voxel` and `voxel-plus` (the same, with half the children mutated instead of 2 %) on
4x4x4 for seeds 1-3 with a pool of 2 processes and prints, per run: the best speed, the
generation it was found in, the best so far at generation 50, the simulations run and the
diversity of the last generation.
"""

from __future__ import annotations

from softevo.core.config import resolve
from softevo.core.physics.evaluation import PoolEvaluator
from softevo.core.search.evolution import Evolution


def main() -> None:
    print(
        f"{'preset':<12}{'seed':>5}{'best m/s':>10}{'found at':>10}{'best@50':>9}"
        f"{'sims':>6}{'diversity':>10}"
    )
    with PoolEvaluator(2) as pool:
        for preset in ("paper-voxel", "voxel-plus"):
            for seed in (1, 2, 3):
                evolution = Evolution.start(resolve({"preset": preset, "seed": seed}))
                evolution.run(pool)
                curve = evolution.curve()
                _, speed, generation = evolution.best_robot()
                print(
                    f"{preset:<12}{seed:>5}{speed:>10.4f}{generation:>10}"
                    f"{curve[49]['best_so_far']:>9.4f}{evolution.evaluations:>6}"
                    f"{curve[-1]['diversity']:>10.3f}",
                    flush=True,
                )


if __name__ == "__main__":
    main()
