"""A mass on a spring: two masses of m joined by one spring of k, free in space (no gravity, far
above the ground), released 5 % stretched. Their relative motion is a damped oscillator of
w_n = sqrt(2 k / m) (200 rad/s), period 2 pi / w_n, decay rate zeta w_n + drag / 2 and damped
frequency sqrt(w_n^2 - decay^2) (analytic_cases.Oscillation). docs/physics.md, "Checked against
closed forms", gives the measured errors; each test prints its own (`pytest -s`).

Tolerances, at the physical profile's derived step (0.433 ms, w_n dt = 0.087):

* undamped period: 5e-4 (measured -3.1e-4: symplectic Euler's (w dt)^2 / 24), second order;
* damped decay rate: 1.5 % (measured 0.36 .. 0.88 %: the dashpot acts on the last step's
  velocity, a relative error of zeta w_n dt), first order; the rate semi-implicit Euler itself
  predicts, -ln(1 - 2 zeta w_n dt) / 2 dt + drag / 2, to 1e-5;
* damped period: 1 % (measured 0.20 .. 0.46 %), first order;
* critical damping (zeta = 1, the profile's own): the curve within 4 % of e0 (measured 2.7 %).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.core.physics.analytic_cases import decay_rate, oscillation, peaks, period


def report(case: str, measured: float, expected: float, tolerance: float) -> float:
    """Print a case's measured relative error beside its tolerance, and return it."""
    error = measured / expected - 1.0
    print(
        f"{case}: measured {measured:.6g}, closed form {expected:.6g}, "
        f"error {error:+.2e} (tolerance {tolerance:.2g})"
    )
    return error


def test_an_undamped_pair_oscillates_at_two_pi_over_omega_n_to_second_order() -> None:
    coarse, fine = oscillation(0.0), oscillation(0.0, divide=2.0)
    closed = 2 * math.pi / coarse.omega_n
    error = report("period, zeta 0", period(coarse), closed, 5e-4)
    assert abs(error) < 5e-4
    finer = period(fine) / closed - 1.0
    assert 3.5 < error / finer < 4.5  # second order: the error quarters when dt halves
    _, heights = peaks(coarse)
    assert np.ptp(heights) < 1e-5 * heights[0]  # no energy lost or gained, peak after peak


@pytest.mark.parametrize(("zeta", "drag"), [(0.1, 0.0), (0.05, 4.0), (0.1, 0.5)])
def test_a_damped_pair_decays_at_zeta_omega_n_plus_half_the_drag(zeta: float, drag: float) -> None:
    osc = oscillation(zeta, drag)
    rate = decay_rate(osc)
    error = report(f"decay rate, zeta {zeta}, drag {drag}", rate, osc.decay, 1.5e-2)
    assert abs(error) < 1.5e-2
    assert rate == pytest.approx(osc.discrete_decay(), rel=1e-5)
    damped = report(f"damped period, zeta {zeta}", period(osc), 2 * math.pi / osc.omega_d, 1e-2)
    assert abs(damped) < 1e-2


def test_the_damped_pairs_error_halves_with_the_step() -> None:
    """First order: the dashpot reads the velocity of the step before."""
    runs = [oscillation(0.1, divide=divide) for divide in (1.0, 2.0, 4.0)]
    rates = [decay_rate(osc) / osc.decay - 1.0 for osc in runs]
    periods = [period(osc) * osc.omega_d / (2 * math.pi) - 1.0 for osc in runs]
    print(f"decay rate errors at dt, dt/2, dt/4: {rates}; damped period errors: {periods}")
    for errors in (rates, periods):
        assert 1.8 < errors[0] / errors[1] < 2.2
        assert 1.8 < errors[1] / errors[2] < 2.2


def test_a_critically_damped_pair_follows_one_plus_omega_t_times_its_exponential() -> None:
    """zeta = 1, the physical profile's material damping: e0 (1 + w_n t) exp(-w_n t), with no
    overshoot."""
    coarse, fine = oscillation(1.0, duration=0.1), oscillation(1.0, divide=2.0, duration=0.1)
    errors = [
        float(np.abs(osc.extension - osc.closed_form(osc.times)).max() / osc.extension[0])
        for osc in (coarse, fine)
    ]
    print(
        f"critical damping: largest error {errors[0]:.2e} of e0 at dt, {errors[1]:.2e} at dt/2 "
        f"(tolerance 4e-2)"
    )
    assert errors[0] < 4e-2
    assert 1.8 < errors[0] / errors[1] < 2.2
    assert coarse.extension.min() >= 0.0
