"""Terrain contact for the kernels: how deep each point is in the ground, and the way out.

Kept apart from `kernels` (which integrates) because it is geometry: one function per terrain
kind of `softevo.core.robots.terrain`, each a loop the compiler vectorises. The flat ground never
comes here (the kernels keep its original arithmetic).

numba's cache of the kernels is keyed on kernels.py alone: after editing this module,
springs.py, integrate.py or `sincos`, touch kernels.py (or remove its __pycache__) so they are
compiled again.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softevo.core.physics.jit import JIT
from softevo.core.robots.terrain import sincos

_sincos = njit(inline="always", **JIT)(sincos)


#: Rows of the kernels' contact scratch (`contact_scratch`).
SCRATCH_ROWS = 12
#: A rough field's cached bound sits this far (relative to the field's reach) above the height it
#: was computed from: far above the rounding of the height and of the bound (< 1e-9 of the reach).
BOUND_MARGIN = 1e-6
#: A cached bound is trusted only where |k| (|x| + |y|) stays below this (rad): there `sincos`
#: holds (it does below 1e6), so the computed field is the true one within 1e-9 of its reach.
BOUND_ANGLES = 1e5


@njit(inline="always", **JIT)
def contact_scratch(n):
    """The kernels' contact scratch for `n` points: rows 0-8 are rewritten every step; rows 9-11
    (a rough field's bound per point, and where it was computed) start with no bound."""
    contact = np.empty((SCRATCH_ROWS, n))
    for m in range(n):
        contact[9, m] = np.inf
        contact[10, m] = 0.0
        contact[11, m] = 0.0
    return contact


@njit(inline="always", **JIT)
def _rough_steepness(tp):
    """The field's steepest slope, sum |weight| |k| (its Lipschitz constant), and its largest
    wavenumber |k|."""
    steepest = 0.0
    wavenumber = 0.0
    for w in range(tp.shape[0] // 4):
        k = math.sqrt(tp[4 * w + 1] * tp[4 * w + 1] + tp[4 * w + 2] * tp[4 * w + 2])
        steepest += abs(tp[4 * w + 4]) * k
        wavenumber = max(wavenumber, k)
    return steepest, wavenumber


@njit(inline="always", **JIT)
def _rough_gather(tp, steepest, wavenumber, x, y, z, step_factor, contact, near):
    """Clear every point's contact and gather into `near` (returning how many) the points whose
    contact must be computed: those that move, are below the field's reach and are not provably
    above the field. A point whose field height h0 was computed at (x0, y0) keeps `bound` = h0 +
    margin; the field is `steepest`-Lipschitz, so at (x, y) it is below bound + steepest (|x -
    x0| + |y - y0|): a point at least that high is out of contact, which is what the full sum
    would say (depth 0, normal e_z), bit for bit."""
    depth, nx, ny, nz = contact[0], contact[1], contact[2], contact[3]
    bound, x0, y0 = contact[9], contact[10], contact[11]
    for m in range(x.shape[0]):  # vectorises: near[m] = 1 where point m is to be evaluated
        depth[m] = 0.0
        nx[m] = 0.0
        ny[m] = 0.0
        nz[m] = 1.0
        cone = bound[m] + steepest * (abs(x[m] - x0[m]) + abs(y[m] - y0[m]))
        held = (z[m] >= cone) & (wavenumber * (abs(x[m]) + abs(y[m])) < BOUND_ANGLES)
        near[m] = (z[m] < tp[0]) & (step_factor[m] > 0.0) & (not held)  # (never moves: 0)
    count = 0
    for m in range(x.shape[0]):  # in place, without a branch: near[m] is read before
        keep = near[m]  # near[count] (count <= m) is written
        near[count] = m
        count += keep
    return count


@njit(inline="always", **JIT)
def _rough_pass(tp, x, y, z, step_factor, contact, near):
    """`contact_pass` on a rough field. Only the points `_rough_gather` keeps (into `near` and
    `contact[4:9]`) are evaluated, wave by wave in a loop over them that vectorises (the
    portable `sincos`); each sums its waves in order, and keeps its height as its new bound."""
    depth, nx, ny, nz = contact[0], contact[1], contact[2], contact[3]
    px, py, h, hx, hy = contact[4], contact[5], contact[6], contact[7], contact[8]
    bound, x0, y0 = contact[9], contact[10], contact[11]
    steepest, wavenumber = _rough_steepness(tp)
    count = _rough_gather(tp, steepest, wavenumber, x, y, z, step_factor, contact, near)
    for c in range(count):
        px[c] = x[near[c]]
        py[c] = y[near[c]]
        h[c] = 0.0
        hx[c] = 0.0
        hy[c] = 0.0
    for w in range(tp.shape[0] // 4):
        kx, ky, phase, weight = tp[4 * w + 1], tp[4 * w + 2], tp[4 * w + 3], tp[4 * w + 4]
        for c in range(count):
            sin_a, cos_a = _sincos(kx * px[c] + ky * py[c] + phase)
            h[c] += weight * cos_a
            slope = weight * sin_a
            hx[c] -= slope * kx
            hy[c] -= slope * ky
    margin = tp[0] * BOUND_MARGIN
    for c in range(count):
        m = near[c]
        touch = z[m] < h[c]
        norm = math.sqrt(1.0 + hx[c] * hx[c] + hy[c] * hy[c])
        depth[m] = (h[c] - z[m]) / norm if touch else 0.0
        nx[m] = -hx[c] / norm if touch else 0.0
        ny[m] = -hy[c] / norm if touch else 0.0
        nz[m] = 1.0 / norm if touch else 1.0
        trusted = wavenumber * (abs(px[c]) + abs(py[c])) < BOUND_ANGLES
        bound[m] = h[c] + margin if trusted else np.inf
        x0[m] = px[c]
        y0[m] = py[c]


@njit(inline="always", **JIT)
def contact_pass(kind, tp, x, y, z, step_factor, contact, near):
    """Penetration depth (m) of every point into the terrain and the surface's unit outward
    normal there (depth 0 and normal e_z: no contact). `kind` and `tp` come from
    `softevo.core.robots.terrain.kernel_params`; see docs/physics.md "Terrain" for edges and faces.

    Into `contact` [0:4]: one loop per kind, written with selects rather than branches, so the
    compiler vectorises it; `contact` [SCRATCH_ROWS, M] (`contact_scratch`) and `near` [M] are
    the kernels' scratch. Both kernels call it on every point, so a robot alone and in a batch
    meet the same ground."""
    depth, nx, ny, nz = contact[0], contact[1], contact[2], contact[3]
    n = x.shape[0]
    if kind == 1:  # slope: tp = tan, cos, sin of the angle; z = x tan
        for m in range(n):
            gap = x[m] * tp[0] - z[m]
            touch = gap > 0.0
            depth[m] = gap * tp[1] if touch else 0.0
            nx[m] = -tp[2] if touch else 0.0
            ny[m] = 0.0
            nz[m] = tp[1] if touch else 1.0
    elif kind == 2:  # steps: tp = height, depth; step i (x in [i D, (i + 1) D)) has top i H
        for m in range(n):
            index = max(np.floor(x[m] / tp[1]), 0.0)
            below = index * tp[0] - z[m]
            face = x[m] - index * tp[1]  # back through the riser the point crossed
            riser = (index >= 1.0) & (face < below)
            touch = below > 0.0
            depth[m] = (face if riser else below) if touch else 0.0
            nx[m] = -1.0 if touch & riser else 0.0
            ny[m] = 0.0
            nz[m] = 0.0 if touch & riser else 1.0
    elif kind == 3:  # rough: tp = the highest the field reaches, then rows kx, ky, phase, weight
        _rough_pass(tp, x, y, z, step_factor, contact, near)
    else:  # hurdles (kind 4): tp = height, spacing, width; bar i >= 1 spans [i S, i S + W]
        for m in range(n):
            index = np.floor(x[m] / tp[1])
            along = x[m] - index * tp[1]
            top = tp[0] - z[m]
            back = tp[2] - along
            bar = (index >= 1.0) & (along <= tp[2]) & (top > 0.0)
            front = (along < top) & (along <= back)  # nearest face: the front, the back, the top
            rear = (not front) & (back < top)
            ground = -z[m]
            d_bar = along if front else (back if rear else top)
            depth[m] = d_bar if bar else (ground if ground > 0.0 else 0.0)
            nx[m] = (-1.0 if front else (1.0 if rear else 0.0)) if bar else 0.0
            ny[m] = 0.0
            nz[m] = 0.0 if bar & (front | rear) else 1.0
