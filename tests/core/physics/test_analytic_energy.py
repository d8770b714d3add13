"""Energy is conserved with no damping: the physical profile with drag, material and contact
damping 0 (its derived step is then 1.05 ms, the undamped limit's 0.8), a 3x2x1 hard and soft
body stretched 5 % and jostled, falling freely from 200 m so it touches nothing for 5 s
(docs/physics.md, "Checked against closed forms").

Kinetic (central-difference velocities) + elastic + gravitational energy. Symplectic Euler
conserves a nearby energy, so the measured one oscillates by O((w dt)^2) and does not drift:
tolerance 1.5 % of the stored elastic energy (130 J) for the largest deviation (measured
0.88 %), 1e-3 for the drift, the mean of the last second minus that of the first (measured
1.1e-4), and the deviation must shrink at least 2.5 times when dt halves (measured 2.9x).
"""

from __future__ import annotations

import numpy as np

from softevo.core.physics import simulate
from tests.core.physics.analytic_cases import (
    elastic_energy,
    energy_error,
    total_energy,
    undamped_body,
)


def test_with_no_damping_the_energy_oscillates_within_bounds_and_does_not_drift() -> None:
    (deviation, drift), (finer, _) = energy_error(), energy_error(divide=2.0)
    print(
        f"energy, no damping, 5 s: largest deviation {deviation:.2e} of the stored energy "
        f"(tolerance 1.5e-2), drift {drift:+.1e} (tolerance 1e-3); at dt/2 {finer:.2e}"
    )
    assert deviation < 1.5e-2
    assert abs(drift) < 1e-3
    assert finer < deviation / 2.5


def test_the_undamped_body_really_vibrates_and_falls() -> None:
    """So the energy's bound is not that of a body at rest: its springs trade their energy
    with its motion, and it falls over 100 m."""
    mech = undamped_body()
    assert mech.sim.step > 1e-3  # the undamped step: stable at w dt < 2
    times, energy, stored = total_energy(mech)
    assert stored > 100.0  # J
    slope = np.polyfit(times, energy, 1)[0] * times[-1] / stored
    assert abs(slope) < 1e-3  # no secular trend over the run
    _, trajectory = simulate(mech, record_every=5)
    assert trajectory is not None
    assert elastic_energy(mech, trajectory.frames).min() < 0.5 * stored
    assert mech.positions[:, 2].mean() - trajectory.frames[-1, :, 2].mean() > 100.0
