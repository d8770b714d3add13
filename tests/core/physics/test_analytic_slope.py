"""A block on a slope, Coulomb friction mu = 0.6 (the friction angle atan 0.6 = 30.96 degrees):
one hard voxel laid flat on a slope at the depth where the ground holds its weight, no drag
(docs/physics.md, "Checked against closed forms").

* Above the friction angle it slides with a = g (sin t - mu cos t). Every base corner slides,
  so friction removes mu Fn dt / m each step and the centre of mass's acceleration is constant:
  semi-implicit Euler integrates it exactly. Tolerance 1e-6 relative (measured <= 6e-10, the
  contact's last ripples), from 0.2 s on (before, the contact settles).
* Below it, it sticks: from 0.2 s to 2 s it moves less than 1e-5 m (measured <= 6.2e-7 m; it
  slips 0.1 .. 1.5 mm in the first 0.2 s while the ground's force builds up).
"""

from __future__ import annotations

import pytest

from tests.core.physics.analytic_bodies import slide


@pytest.mark.parametrize("angle", [32.0, 40.0, 50.0])
def test_above_the_friction_angle_the_block_slides_at_g_sin_minus_mu_cos(angle: float) -> None:
    run = slide(angle)
    measured, closed = run.acceleration(), run.closed_form
    error = measured / closed - 1.0
    print(
        f"slope {angle} deg: acceleration {measured:.9f} m/s^2, closed form {closed:.9f} "
        f"({error:+.1e}, tolerance 1e-6)"
    )
    assert abs(error) < 1e-6


@pytest.mark.parametrize("angle", [10.0, 20.0, 30.0])
def test_below_the_friction_angle_the_block_sticks(angle: float) -> None:
    run = slide(angle)
    print(
        f"slope {angle} deg: moved {run.moved():+.2e} m from 0.2 s to 2 s (tolerance 1e-5 m), "
        f"{run.along[int(run.times.searchsorted(0.2))]:.2e} m before"
    )
    assert run.closed_form == 0.0
    assert abs(run.moved()) < 1e-5
