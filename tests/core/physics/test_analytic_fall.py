"""Free fall, with and without drag, in the physical profile (a hard cube dropped from 100 m,
never near the ground; docs/physics.md, "Checked against closed forms").

* No drag: z(t) = z0 - g t^2 / 2. Semi-implicit Euler's exact discrete solution is
  z_n = z0 - g dt^2 n (n + 1) / 2 = z0 - g t^2 / 2 - g dt t / 2, so the tolerance is that
  first-order term, g dt t / 2 (4.2 mm after 2 s at the derived 0.433 ms step), to 1e-9 m, and
  the speed is exactly g t (to 1e-9 m/s).
* Drag c: v(t) = (g / c)(1 - e^-ct) towards the terminal g / c. The discrete velocity is
  v_n = v* (1 - f^n) with f = e^-c dt, so f^n = e^-ct exactly and only the terminal speed
  differs: v* = g dt f / (1 - f) = (g / c)(1 - c dt / 2 + ...). Tolerance on the speed: c dt of
  g / c (measured c dt / 2 = 4.3e-4 at c = 2 s^-1), first order.
"""

from __future__ import annotations

import numpy as np

from tests.core.physics.analytic_cases import G, fall


def test_a_dropped_cube_falls_g_t_squared_over_two_ahead_by_g_dt_t_over_two() -> None:
    run = fall()
    height, speed = run.closed_form()
    lag = G * run.step * run.times / 2  # how far semi-implicit Euler is ahead: g dt t / 2
    error = float(np.abs(run.height - height).max())
    print(
        f"free fall: largest |z - (z0 - g t^2 / 2)| {error:.3e} m over {run.times[-1]:.1f} s "
        f"(tolerance g dt t / 2 = {lag[-1]:.3e} m)"
    )
    np.testing.assert_allclose(height - run.height, lag, rtol=0, atol=1e-9)
    np.testing.assert_allclose(run.speed, speed, rtol=0, atol=1e-9)
    assert error <= lag[-1] + 1e-9


def test_drag_brings_the_fall_to_g_over_c_along_the_exponential() -> None:
    drag = 2.0
    coarse, fine = fall(drag, duration=4.0), fall(drag, divide=2.0, duration=4.0)
    errors = []
    for run in (coarse, fine):
        _, speed = run.closed_form()
        errors.append(float(np.abs(run.speed - speed).max() / (G / drag)))
    terminal = coarse.speed[-1] / (1 - np.exp(-drag * coarse.times[-1]))
    print(
        f"drag {drag} s^-1: terminal speed {terminal:.6f} m/s against g / c = {G / drag} "
        f"({terminal / (G / drag) - 1:+.2e}); largest speed error {errors[0]:.2e} of g / c at "
        f"dt, {errors[1]:.2e} at dt/2 (tolerance c dt = {drag * coarse.step:.2e})"
    )
    assert errors[0] < drag * coarse.step
    assert 1.9 < errors[0] / errors[1] < 2.1  # first order
    height, _ = coarse.closed_form()
    fallen = coarse.height[0] - coarse.height[-1]
    assert abs(coarse.height[-1] - height[-1]) < drag * coarse.step * fallen
