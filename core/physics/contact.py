"""Terrain contact for the kernels: how deep each point is in the ground, and the way out.

Kept apart from `kernels` (which integrates) because it is geometry: one function per terrain
kind of `softevo.core.terrain`, each a loop the compiler vectorises. The flat ground never comes
here (the kernels keep its original arithmetic).

numba's cache of the kernels is keyed on kernels.py alone: after editing this module or
`sincos`, touch kernels.py (or remove its __pycache__) so they are compiled again.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from softevo.core.terrain import sincos

#: Options of every kernel: cached, callable without the GIL, plain IEEE arithmetic (numpy's error
#: model and no fastmath), no bounds checks.
JIT = {"cache": True, "nogil": True, "error_model": "numpy", "boundscheck": False}

_sincos = njit(inline="always", **JIT)(sincos)


@njit(inline="always", **JIT)
def _rough_pass(tp, x, y, z, step_factor, contact, near):
    """`contact_pass` on a rough field. Only the points that move and are below the highest the
    field reaches (gathered into `near` and `contact[4:9]`) are evaluated, wave by wave in a
    loop over them that vectorises (the portable `sincos`); each sums its waves in order."""
    depth, nx, ny, nz = contact[0], contact[1], contact[2], contact[3]
    px, py, h, hx, hy = contact[4], contact[5], contact[6], contact[7], contact[8]
    for m in range(x.shape[0]):
        depth[m] = 0.0
        nx[m] = 0.0
        ny[m] = 0.0
        nz[m] = 1.0
    count = 0
    for m in range(x.shape[0]):  # without a branch: each point is written, kept if it is near
        near[count] = m
        count += (z[m] < tp[0]) & (step_factor[m] > 0.0)  # (a point that never moves: 0)
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
    for c in range(count):
        m = near[c]
        touch = z[m] < h[c]
        norm = math.sqrt(1.0 + hx[c] * hx[c] + hy[c] * hy[c])
        depth[m] = (h[c] - z[m]) / norm if touch else 0.0
        nx[m] = -hx[c] / norm if touch else 0.0
        ny[m] = -hy[c] / norm if touch else 0.0
        nz[m] = 1.0 / norm if touch else 1.0


@njit(inline="always", **JIT)
def contact_pass(kind, tp, x, y, z, step_factor, contact, near):
    """Penetration depth (m) of every point into the terrain and the surface's unit outward
    normal there (depth 0 and normal e_z: no contact). `kind` and `tp` come from
    `softevo.core.terrain.kernel_params`; see docs/physics.md "Terrain" for edges and faces.

    Into `contact` [0:4]: one loop per kind, written with selects rather than branches, so the
    compiler vectorises it; `contact` [9, M] and `near` [M] are the kernels' scratch. Both
    kernels call it on every point, so a robot alone and in a batch meet the same ground."""
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
