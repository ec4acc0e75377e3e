"""numba-compiled octaves of the procedural clouds' noise (:func:`.clouds.perlin_fbm`, :func:`.clouds.worley_fbm`).

One call adds one octave at every point: [Perlin2002] gradient noise or [Worley1996] cellular noise (F1) on a
periodic lattice whose random tables (a gradient index, or a feature point, per cell) are drawn by the caller
with numpy's generator, so the fields are those of the seed as before. The arithmetic is that of the numpy
evaluation it replaced, operation by operation and in the same order (the corners' contributions summed in the
order of their index, the dot products and squared distances summed over the axes in order, no fused
multiply-adds): the values are the same to the last bit, so the cover threshold (a quantile of the coverage map)
and the cut of thin liquid water fall on the same voxels. 2D (the coverage map) and 3D (the erosion) points each
have their own loop body, so that the corners and neighbours are unrolled, with no arrays allocated per point.
Two changes of the arithmetic leave the values unchanged: the neighbours' indices are wrapped into the period
by adding or subtracting it once (integer divisions were most of the cost), and Worley's noise takes the square
root of the smallest squared distance instead of the smallest of the distances (the square root is correctly
rounded in IEEE 754 and so monotonic: the two are the same number), one square root per point instead of 9 or 27.

Imported on first use by :mod:`.clouds`, so that importing the atmosphere package does not import numba.
"""

from __future__ import annotations

import math

from ..jit import helper, inline, kernel

__all__ = ["add_perlin_octave", "add_worley_octave"]


@inline
def _fade(t):
    """Perlin's quintic fade ``6t^5 - 15t^4 + 10t^3`` ([Perlin2002]) of ``t`` in [0, 1] [-], evaluated as
    ``t^3 (t (6t - 15) + 10)`` (this grouping, rounded as it is, is part of the fields' definition)."""
    return t * t * t * (t * (t * 6.0 - 15.0) + 10.0)


@inline
def _wrap(i, p):
    """``i % p`` [cell] for ``i`` in ``[-1, 2 p)`` without an integer division (the neighbours of a cell
    whose index is already wrapped into ``[0, p)``)."""
    if i < 0:
        return i + p
    if i >= p:
        return i - p
    return i


@helper
def _perlin_2d(x, y, px, py, grads, gradients):
    """[Perlin2002] gradient noise at lattice point (``x``, ``y``) [lattice units], periodic with ``px`` x ``py``
    cells; ``grads`` (px * py,) gradient index per lattice node (C order), ``gradients`` (12, 3) the edge
    gradients (their first two components); about [-1, 1]."""
    cx = math.floor(x)
    cy = math.floor(y)
    fx = x - cx
    fy = y - cy
    wx = _fade(fx)
    wy = _fade(fy)
    nx = int(cx) % px
    ny = int(cy) % py
    out = 0.0
    for corner in range(4):  # corner bit k is the offset along axis k, summed in the corners' order
        ox = corner & 1
        oy = (corner >> 1) & 1
        g = grads[_wrap(nx + ox, px) * py + _wrap(ny + oy, py)]
        dot = gradients[g, 0] * (fx - ox) + gradients[g, 1] * (fy - oy)
        weight = (wx if ox else 1.0 - wx) * (wy if oy else 1.0 - wy)
        out += weight * dot
    return out


@helper
def _perlin_3d(x, y, z, px, py, pz, grads, gradients):
    """[Perlin2002] gradient noise at lattice point (``x``, ``y``, ``z``) [lattice units], periodic with
    ``px`` x ``py`` x ``pz`` cells; ``grads`` (px * py * pz,) gradient index per lattice node (C order),
    ``gradients`` (12, 3) the edge gradients; about [-1, 1]."""
    cx = math.floor(x)
    cy = math.floor(y)
    cz = math.floor(z)
    fx = x - cx
    fy = y - cy
    fz = z - cz
    wx = _fade(fx)
    wy = _fade(fy)
    wz = _fade(fz)
    nx = int(cx) % px
    ny = int(cy) % py
    nz = int(cz) % pz
    out = 0.0
    for corner in range(8):
        ox = corner & 1
        oy = (corner >> 1) & 1
        oz = (corner >> 2) & 1
        g = grads[(_wrap(nx + ox, px) * py + _wrap(ny + oy, py)) * pz + _wrap(nz + oz, pz)]
        dot = gradients[g, 0] * (fx - ox) + gradients[g, 1] * (fy - oy) + gradients[g, 2] * (fz - oz)
        weight = (wx if ox else 1.0 - wx) * (wy if oy else 1.0 - wy) * (wz if oz else 1.0 - wz)
        out += weight * dot
    return out


@helper
def _worley_2d(x, y, px, py, feats):
    """[Worley1996] cellular noise F1 at lattice point (``x``, ``y``): distance [lattice units] to the nearest
    feature point of the 3 x 3 cells around it, periodic with ``px`` x ``py`` cells; ``feats`` (px * py, 2) the
    feature point's offset in its cell (C order)."""
    ix = int(math.floor(x))
    iy = int(math.floor(y))
    wx = ix % px
    wy = iy % py
    best = math.inf
    for a in range(-1, 2):
        ca = _wrap(wx + a, px) * py
        for b in range(-1, 2):
            c = ca + _wrap(wy + b, py)
            dx = x - ((ix + a) + feats[c, 0])
            dy = y - ((iy + b) + feats[c, 1])
            best = min(best, dx * dx + dy * dy)
    return math.sqrt(best)


@helper
def _worley_3d(x, y, z, px, py, pz, feats):
    """[Worley1996] cellular noise F1 at lattice point (``x``, ``y``, ``z``): distance [lattice units] to the
    nearest feature point of the 3 x 3 x 3 cells around it, periodic with ``px`` x ``py`` x ``pz`` cells;
    ``feats`` (px * py * pz, 3) the feature point's offset in its cell (C order)."""
    ix = int(math.floor(x))
    iy = int(math.floor(y))
    iz = int(math.floor(z))
    wx = ix % px
    wy = iy % py
    wz = iz % pz
    best = math.inf
    for a in range(-1, 2):
        ca = _wrap(wx + a, px) * py
        for b in range(-1, 2):
            cb = (ca + _wrap(wy + b, py)) * pz
            for e in range(-1, 2):
                c = cb + _wrap(wz + e, pz)
                dx = x - ((ix + a) + feats[c, 0])
                dy = y - ((iy + b) + feats[c, 1])
                dz = z - ((iz + e) + feats[c, 2])
                best = min(best, dx * dx + dy * dy + dz * dz)
    return math.sqrt(best)


@kernel
def add_perlin_octave(total, points, scale, period, grads, gradients, amplitude):
    """``total[i] += amplitude * perlin(scale * points[i])`` for the points (n, d), d = 2 or 3 [lattice units of
    the first octave]; ``scale`` the octave's frequency (a power of 2, so the scaled points are exact),
    ``period`` (d,) its lattice period [cells], ``grads`` (prod(period),) its gradient indices (C order),
    ``gradients`` (12, 3) [Perlin2002]'s edge gradients, ``amplitude`` [-]."""
    n, d = points.shape
    if d == 2:
        px, py = period[0], period[1]
        for i in range(n):
            total[i] += amplitude * _perlin_2d(points[i, 0] * scale, points[i, 1] * scale, px, py, grads, gradients)
    else:
        px, py, pz = period[0], period[1], period[2]
        for i in range(n):
            total[i] += amplitude * _perlin_3d(points[i, 0] * scale, points[i, 1] * scale, points[i, 2] * scale,
                                               px, py, pz, grads, gradients)


@kernel
def add_worley_octave(total, points, scale, period, feats, amplitude):
    """``total[i] += amplitude * (1 - F1(scale * points[i]))`` for the points (n, d), d = 2 or 3 [lattice units of
    the first octave]; ``scale`` the octave's frequency (a power of 2), ``period`` (d,) its lattice period [cells],
    ``feats`` (prod(period), d) the feature points' offsets in their cells (C order), ``amplitude`` [-]."""
    n, d = points.shape
    if d == 2:
        px, py = period[0], period[1]
        for i in range(n):
            total[i] += amplitude * (1.0 - _worley_2d(points[i, 0] * scale, points[i, 1] * scale, px, py, feats))
    else:
        px, py, pz = period[0], period[1], period[2]
        for i in range(n):
            total[i] += amplitude * (1.0 - _worley_3d(points[i, 0] * scale, points[i, 1] * scale,
                                                      points[i, 2] * scale, px, py, pz, feats))

