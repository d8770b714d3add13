"""The rough field's per-point bound (core/physics/contact.py): a point it lets skip the wave sum
gets the contact the full sum gives, to the last bit, and it does skip points."""

from __future__ import annotations

import numpy as np
import pytest

from softevo.core.physics.contact import (
    _rough_gather,
    _rough_steepness,
    contact_pass,
    contact_scratch,
)
from softevo.core.robots.terrain import Rough, kernel_params

FIELD = Rough(amplitude=0.2, wavelength=1.5, seed=4)


def walk(n: int, steps: int, seed: int) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Points that wander over the field, from 0.05 below it to above its reach, so some enter
    and leave contact on the way."""
    rng = np.random.default_rng(seed)
    x, y = rng.uniform(-5.0, 5.0, n), rng.uniform(-5.0, 5.0, n)
    z = FIELD.surface(x, y) + rng.uniform(-0.05, 0.3, n)
    frames = []
    for _ in range(steps):
        x = x + rng.normal(0.0, 2e-3, n)
        y = y + rng.normal(0.0, 2e-3, n)
        z = z + rng.normal(0.0, 2e-3, n)
        frames.append((x, y, z))
    return frames


def gathered(tp: np.ndarray, frame: tuple, contact: np.ndarray) -> np.ndarray:
    """The points of `frame` the gather keeps with the bounds in `contact`."""
    steepest, wavenumber = _rough_steepness(tp)
    x, y, z = frame
    near = np.empty(x.shape[0], dtype=np.int64)
    count = _rough_gather(tp, steepest, wavenumber, x, y, z, np.ones_like(x), contact, near)
    return near[:count]


def test_a_point_the_bound_skips_gets_the_full_sums_contact_bit_for_bit() -> None:
    kind, tp = kernel_params(FIELD)
    frames = walk(3000, 60, seed=1)
    n = frames[0][0].shape[0]
    kept = contact_scratch(n)  # bounds carried from step to step, as in the kernels
    near = np.empty(n, dtype=np.int64)
    touching = []
    for frame in frames:
        with_bounds = gathered(tp, frame, kept).size
        without = gathered(tp, frame, contact_scratch(n)).size
        fresh = contact_scratch(n)
        contact_pass(kind, tp, *frame, np.ones(n), kept, near)
        contact_pass(kind, tp, *frame, np.ones(n), fresh, near)
        assert kept[:4].tobytes() == fresh[:4].tobytes()  # depth and normal of every point
        touching.append(kept[0] > 0.0)
    assert with_bounds < 0.5 * without  # the last step skipped most of the points below reach
    crossed = np.any(touching, axis=0) & ~np.all(touching, axis=0)
    assert crossed.sum() > 10  # points entered or left contact while bounds were kept
    assert touching[-1].sum() > 100


def test_no_bound_is_kept_where_the_fields_angles_leave_sincos_range() -> None:
    kind, tp = kernel_params(FIELD)
    x = np.array([1.0, 1e6, -3e5, np.nan, 2.0])
    y = np.array([0.5, 0.0, 1.0, 0.0, np.inf])
    z = np.full(5, -0.5)  # below the field everywhere: every point is evaluated
    contact = contact_scratch(5)
    contact_pass(kind, tp, x, y, z, np.ones(5), contact, np.empty(5, dtype=np.int64))
    assert np.isfinite(contact[9, 0]) and contact[9, 0] == pytest.approx(
        float(FIELD.surface(1.0, 0.5)), abs=1e-6
    )
    assert np.isinf(contact[9, 1:]).all()  # far away, NaN or infinite: no bound
    higher = np.full(5, 0.19)  # above the first point's field, below the field's reach
    assert gathered(tp, (x, y, higher), contact).tolist() == [1, 2, 3, 4]  # evaluated again
