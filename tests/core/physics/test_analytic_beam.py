"""Voxel bodies under their own weight against bar and beam theory, with the lattice's elastic
constants derived in analytic_bodies.py (E = 144/19 k/a with free sides, EI = 4/3 k a^3 and
GA = 10/3 k a for a beam one voxel thick; docs/physics.md, "Checked against closed forms").

* A 1x1x8 column on a frictionless ground (its base spreads freely): each plane's shortening
  against a stack of springs of stiffness E a, within 1 % of the top's (measured 0.09 %; the
  rest is the geometry's nonlinearity at 0.26 % strain). On a ground with friction 0.6 the base
  is held, and the column lies between that and C11 = 28/3 k/a, the modulus with its sides held
  (measured 1.8 % stiffer than E, against 23 % for C11).
* A 1x1xN cantilever clamped at one end (its first plane pinned), loaded so Euler-Bernoulli
  predicts a tip deflection of L / 200 (linear): its tip within 2 % of Euler-Bernoulli for
  N >= 6 (measured +0.2 %, -0.5 %, -0.8 % at N = 6, 8, 16). Shorter beams shear: at N = 3 the
  tip is 7 % past Euler-Bernoulli, so beam theory is checked from L = 6 a on, and not below.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.core.physics.analytic_bodies import C11, cantilever, column


def test_a_column_on_a_frictionless_ground_shortens_as_a_stack_of_springs() -> None:
    run = column(8)
    closed = run.closed_form()
    error = float(np.abs(run.shortening - closed).max() / closed[-1])
    print(
        f"column 1x1x8, no friction: top plane down {run.shortening[-1]:.6e} m, closed form "
        f"{closed[-1]:.6e} m; largest plane error {error:.1e} of it (tolerance 1e-2)"
    )
    assert error < 1e-2


def test_a_column_held_at_its_base_by_friction_lies_between_free_and_held_sides() -> None:
    run = column(8, friction=0.6)
    free, held = run.closed_form()[-1], run.closed_form(C11)[-1]
    print(
        f"column 1x1x8, friction 0.6: top down {run.shortening[-1]:.6e} m, free sides "
        f"{free:.6e}, held sides {held:.6e}"
    )
    assert held < run.shortening[-1] < free


@pytest.mark.parametrize("voxels", [6, 8, 16])
def test_a_cantilever_bends_as_euler_bernoulli_with_the_lattices_stiffness(voxels: int) -> None:
    run = cantilever(voxels)
    print(
        f"cantilever of {voxels}: tip {run.deflection[-1]:.6e} m, {run.error:+.2e} from "
        f"Euler-Bernoulli (tolerance 2e-2)"
    )
    assert abs(run.error) < 2e-2


def test_a_short_cantilever_shears_past_euler_bernoulli() -> None:
    """Where beam theory stops: a beam three voxels long is no slender beam."""
    run = cantilever(3)
    print(f"cantilever of 3: {run.error:+.2e} from Euler-Bernoulli")
    assert run.error > 0.05
