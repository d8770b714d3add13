"""The analytic validation suite in pictures: `python bench/analytic_figures.py [--out DIR]`.

Runs every case of tests/core/physics/analytic_cases.py and analytic_bodies.py (a mass on a
spring, free fall, a block on a slope, a column and a cantilever under their own weight, energy
without damping), prints each one's measured error against its closed form, and draws one PNG
per case, simulated against closed form, as DIR/physics_<case>.png (default docs/img). The
tests check the same numbers (tests/core/physics/test_analytic_*.py); docs/physics.md ("Checked
against closed forms") shows the figures.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the cases live with the tests that check them

from tests.core.physics import analytic_bodies as bodies  # noqa: E402
from tests.core.physics import analytic_cases as cases  # noqa: E402

DIVIDES = (1.0, 2.0, 4.0, 8.0)


def figure(title: str) -> tuple[Figure, list]:
    """A two-panel figure (matplotlib's Agg, no screen)."""
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    fig.suptitle(title)
    return fig, list(fig.subplots(1, 2))


def save(fig: Figure, out: Path, case: str) -> None:
    path = out / f"physics_{case}.png"
    fig.savefig(path, dpi=110)
    print(f"  wrote {path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}")


def oscillator_errors() -> dict[str, list[float]]:
    """Relative errors at dt / 1 .. dt / 8: undamped period, damped decay rate (zeta 0.1) and
    the critically damped curve's largest error (of e0)."""
    errors: dict[str, list[float]] = {"period, zeta 0": [], "decay rate, zeta 0.1": []}
    errors["curve, zeta 1 (of e0)"] = []
    for divide in DIVIDES:
        free, damped = cases.oscillation(0.0, divide=divide), cases.oscillation(0.1, divide=divide)
        critical = cases.oscillation(1.0, divide=divide, duration=0.1)
        errors["period, zeta 0"].append(abs(cases.period(free) * free.omega_n / (2 * math.pi) - 1))
        errors["decay rate, zeta 0.1"].append(abs(cases.decay_rate(damped) / damped.decay - 1))
        gap = np.abs(critical.extension - critical.closed_form(critical.times)).max()
        errors["curve, zeta 1 (of e0)"].append(float(gap / critical.extension[0]))
    return errors


def oscillator(out: Path) -> None:
    fig, (left, right) = figure(
        "A mass on a spring: two 0.1 kg masses, k = 2000 N/m, free in space"
    )
    for zeta, colour in ((0.0, "tab:blue"), (0.1, "tab:orange"), (1.0, "tab:green")):
        osc = cases.oscillation(zeta, duration=0.1)
        fine = np.linspace(0, osc.times[-1], 2000)
        left.plot(
            fine * 1e3,
            osc.closed_form(fine) * 1e3,
            color=colour,
            lw=1,
            label=f"closed form, zeta {zeta}",
        )
        left.plot(
            osc.times[::6] * 1e3,
            osc.extension[::6] * 1e3,
            "o",
            ms=2.5,
            color=colour,
            label=f"simulated, zeta {zeta}",
        )
    left.set(
        xlabel="t (ms)",
        ylabel="extension d - L (mm)",
        title="at the physical profile's step (0.433 ms)",
    )
    left.set_ylim(-55, 85)
    left.legend(fontsize=7, ncol=3, loc="upper center")
    step = cases.oscillation(0.0).step
    steps = [step / divide * 1e3 for divide in DIVIDES]
    print("mass on a spring (relative errors at dt, dt/2, dt/4, dt/8):")
    for (name, errors), marker in zip(oscillator_errors().items(), "osD", strict=True):
        right.loglog(steps, errors, marker + "-", label=name)
        print(f"  {name}: " + ", ".join(f"{e:.2e}" for e in errors))
    for order, scale in ((1, 0.02), (2, 6e-4)):
        right.loglog(steps, [scale * (s / steps[0]) ** order for s in steps], "k:", lw=0.8)
        right.annotate(
            f"order {order}", (steps[-1], scale * (steps[-1] / steps[0]) ** order), fontsize=8
        )
    right.set(xlabel="dt (ms)", ylabel="relative error", title="error against the closed form")
    right.legend(fontsize=8)
    save(fig, out, "oscillator")


def free_fall(out: Path) -> None:
    fig, (left, right) = figure("Free fall: a hard cube dropped from 100 m (drag 0 and 2 s^-1)")
    print("free fall:")
    for drag, colour in ((0.0, "tab:blue"), (2.0, "tab:orange")):
        run = cases.fall(drag, duration=4.0)
        height, speed = run.closed_form()
        every = slice(None, None, 400)
        left.plot(
            run.times, run.height[0] - height, color=colour, lw=1, label=f"closed form, drag {drag}"
        )
        left.plot(
            run.times[every],
            run.height[0] - run.height[every],
            "o",
            ms=3,
            color=colour,
            label=f"simulated, drag {drag}",
        )
        right.plot(run.times, speed, color=colour, lw=1, label=f"closed form, drag {drag}")
        right.plot(
            run.times[every],
            run.speed[every],
            "o",
            ms=3,
            color=colour,
            label=f"simulated, drag {drag}",
        )
        gap = np.abs(run.height - height).max()
        speed_gap = np.abs(run.speed - speed).max()
        print(
            f"  drag {drag}: largest height error {gap:.3e} m, speed error {speed_gap:.3e} m/s "
            f"(g dt t / 2 at the end: {cases.G * run.step * run.times[-1] / 2:.3e} m)"
        )
        if drag:
            right.axhline(cases.G / drag, color=colour, ls="--", lw=0.8, label="terminal g / c")
    left.set(xlabel="t (s)", ylabel="fallen (m)", title="z0 - z")
    right.set(
        xlabel="t (s)", ylabel="downward speed (m/s)", title="speed: g t, or (g / c)(1 - exp(-c t))"
    )
    left.legend(fontsize=8)
    right.legend(fontsize=8)
    save(fig, out, "free_fall")


def slope(out: Path) -> None:
    fig, (left, right) = figure(
        "A hard voxel on a slope, Coulomb friction mu = 0.6 (friction angle 30.96 deg)"
    )
    print("block on a slope (acceleration down the slope from 0.2 s on):")
    for angle in (20.0, 30.0, 32.0, 40.0, 50.0):
        run = bodies.slide(angle)
        left.plot(
            run.times, run.closed_form * run.times**2 / 2, lw=1, label=f"{angle:g} deg: a t^2 / 2"
        )
        left.plot(run.times[::12], run.along[::12], "o", ms=2.5, color=left.lines[-1].get_color())
        error = run.acceleration() - run.closed_form
        print(
            f"  {angle:g} deg: a = {run.acceleration():.9f} m/s^2, closed form "
            f"{run.closed_form:.9f} ({error:+.1e}); moved {run.moved():+.2e} m after 0.2 s"
        )
    left.set(
        xlabel="t (s)",
        ylabel="moved down the slope (m)",
        title="lines: closed form; dots: simulated",
    )
    left.legend(fontsize=8)
    angles = np.arange(0.0, 56.0, 2.5)
    measured = [bodies.slide(angle).acceleration() for angle in angles]
    fine = np.linspace(0, 55, 300)
    closed = np.maximum(
        cases.G * (np.sin(np.radians(fine)) - bodies.MU * np.cos(np.radians(fine))), 0
    )
    right.plot(fine, closed, lw=1, label="g (sin t - mu cos t), 0 below the friction angle")
    right.plot(angles, measured, "o", ms=4, label="simulated (parabola fit)")
    right.axvline(math.degrees(math.atan(bodies.MU)), color="grey", ls=":", lw=0.8)
    right.set(
        xlabel="slope angle (deg)",
        ylabel="acceleration (m/s^2)",
        title="acceleration against angle",
    )
    right.legend(fontsize=8)
    save(fig, out, "slope")


def column(out: Path) -> None:
    fig, (left, right) = figure("A 1x1xN column of hard voxels under its own weight")
    free, held = bodies.column(10), bodies.column(10, friction=0.6)
    planes = np.arange(11)
    left.plot(
        planes,
        free.closed_form() * 1e3,
        "-",
        lw=1,
        label="stack of springs, E = 144/19 k/a (sides free)",
    )
    left.plot(
        planes, free.closed_form(bodies.C11) * 1e3, "--", lw=1, label="C11 = 28/3 k/a (sides held)"
    )
    left.plot(planes, free.shortening * 1e3, "o", ms=4, label="simulated, friction 0")
    left.plot(planes, held.shortening * 1e3, "s", ms=4, mfc="none", label="simulated, friction 0.6")
    left.set(xlabel="plane (a = 1 m above the base)", ylabel="came down (mm)", title="N = 10")
    left.legend(fontsize=8)
    print("column (top plane's shortening against the stack of springs):")
    sizes = np.arange(1, 13)
    for friction, marker in ((0.0, "o-"), (0.6, "s-")):
        errors = [
            bodies.column(int(n), friction).shortening[-1]
            / bodies.column(int(n), friction).closed_form()[-1]
            - 1
            for n in sizes
        ]
        right.plot(sizes, np.array(errors) * 100, marker, ms=4, label=f"friction {friction}")
        print(
            f"  friction {friction}: "
            + ", ".join(f"N={n} {e:+.2e}" for n, e in zip(sizes, errors, strict=True))
        )
    right.axhspan(-1, 1, color="tab:green", alpha=0.15, label="the test's 1 % (friction 0)")
    right.set(xlabel="voxels N", ylabel="error (%)", title="top plane against the closed form")
    right.legend(fontsize=8)
    save(fig, out, "column")


def cantilever(out: Path) -> None:
    fig, (left, right) = figure(
        "A 1x1xN cantilever of hard voxels, clamped at x = 0, under its own weight"
    )
    run = bodies.cantilever(12)
    fine = np.linspace(0, 12, 200)
    left.plot(
        fine,
        bodies.beam_deflection(12, fine, run.gravity) * 1e3,
        lw=1,
        label="Euler-Bernoulli, EI = 4/3 k a^3",
    )
    left.plot(
        fine,
        bodies.beam_deflection(12, fine, run.gravity, shear=True) * 1e3,
        "--",
        lw=1,
        label="with Timoshenko shear, GA = 10/3 k a",
    )
    left.plot(run.positions, run.deflection * 1e3, "o", ms=4, label="simulated")
    left.set(
        xlabel="x (m)",
        ylabel="deflection (mm)",
        title=f"N = 12, g = {run.gravity:.3f} m/s^2 (tip L / 200)",
    )
    left.legend(fontsize=8)
    sizes = (2, 3, 4, 6, 8, 12, 16, 24, 32)
    errors = [bodies.cantilever(n).error for n in sizes]
    print(
        "cantilever (tip against Euler-Bernoulli): "
        + ", ".join(f"N={n} {e:+.2e}" for n, e in zip(sizes, errors, strict=True))
    )
    right.plot(sizes, np.array(errors) * 100, "o-", label="simulated tip / Euler-Bernoulli - 1")
    right.axhspan(-2, 2, color="tab:green", alpha=0.15, label="the test's 2 % (N >= 6)")
    right.axhline(0, color="grey", lw=0.8)
    right.set(xlabel="voxels N (L / a)", ylabel="error (%)", title="where beam theory holds")
    right.set_xticks(sizes)
    right.legend(fontsize=8)
    save(fig, out, "cantilever")


def energy(out: Path) -> None:
    fig, (left, right) = figure("Energy with no damping: a 3x2x1 body vibrating in free fall")
    print("energy (largest deviation and drift, of the stored elastic energy):")
    deviations = []
    for divide in (1.0, 2.0, 4.0):
        mech = cases.undamped_body(divide, duration=14.0, drop=1000.0)
        times, total, stored = cases.total_energy(mech)
        change = (total - total[0]) / stored
        second = round(1.0 / mech.sim.step)
        deviations.append(float(np.abs(change).max()))
        print(
            f"  dt {mech.sim.step * 1e3:.3f} ms: deviation {deviations[-1]:.2e}, drift "
            f"{change[-second:].mean() - change[:second].mean():+.1e} over 14 s"
        )
        left.plot(times, change * 100, lw=0.5, label=f"dt = {mech.sim.step * 1e3:.3f} ms")
    left.set(
        xlabel="t (s)",
        ylabel="(E - E0) / stored (%)",
        title="kinetic + elastic + gravity, 14 s falling 960 m",
    )
    left.legend(fontsize=8)
    steps = [cases.undamped_body(d).sim.step * 1e3 for d in (1.0, 2.0, 4.0)]
    right.loglog(steps, deviations, "o-", label="largest deviation")
    right.loglog(steps, [deviations[0] * (s / steps[0]) ** 2 for s in steps], "k:", label="order 2")
    right.set(xlabel="dt (ms)", ylabel="largest |E - E0| / stored", title="bounded, and O(dt^2)")
    right.legend(fontsize=8)
    save(fig, out, "energy")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "img")
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    for case in (oscillator, free_fall, slope, column, cantilever, energy):
        case(out)


if __name__ == "__main__":
    main()
