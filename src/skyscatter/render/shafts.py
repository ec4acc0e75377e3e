"""Light shafts in a landscape: the length of each view ray that lies in the terrain's shadow.

Bruneton & Neyret ([Bruneton2008] Sec. 5) render light shafts by moving the
total length ``l`` of a view ray that lies in terrain shadow to one end of the ray (Eqs. 17-18,
:mod:`skyscatter.aerial.bruneton`). The paper finds ``l`` with a shadow-volume pass on the GPU; here it is
estimated on the CPU (:func:`shadow_lengths`) by marching each view ray and casting a shadow ray towards the sun
with the exact heightfield tracer (:func:`skyscatter.render.heightfield.trace_ray`) at every sample: ``samples``
equal steps up to the ray's end, and each step whose two ends disagree (one lit, one shadowed) is bisected
``refine`` times to place the light/shadow boundary. A ray crossing one shadow boundary per step is measured to
within ``step / 2**(refine + 1)``; shadows thinner than a step between two samples of the same state are missed.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..aerial.base import DEFAULT_REFINE, DEFAULT_SHADOW_SAMPLES
from ..conventions import as_directions
from ..errors import InvalidParameterError
from ..jit import inline, parallel_kernel
from ..validation import whole_number
from .heightfield import HeightfieldTracer, trace_ray
from .terrain import Terrain

__all__ = ["DEFAULT_REFINE", "DEFAULT_SHADOW_SAMPLES", "shadow_lengths"]


@inline
def _in_shadow(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, px, py, pz, sx, sy, sz, t_min, t_max):
    """True if the point sees the terrain towards the sun (the tracer's shadow test)."""
    return trace_ray(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, px, py, pz, sx, sy, sz,
                  t_min, t_max) != np.inf


@parallel_kernel
def _shadow_lengths(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, origins, dirs, dist, sun,
                    samples, refine, t_min, t_max, end_offset, out):
    n = dirs.shape[0]
    stride = 0 if origins.shape[0] == 1 else 1
    sx, sy, sz = sun[0], sun[1], sun[2]
    for i in numba.prange(n):
        k = i * stride
        ox, oy, oz = origins[k, 0], origins[k, 1], origins[k, 2]
        dx, dy, dz = dirs[i, 0], dirs[i, 1], dirs[i, 2]
        s = dist[i]
        out[i] = 0.0
        if not s > 0.0:
            continue
        # With the sun above the horizon nothing above the highest terrain is shadowed: march only the
        # part of the ray below it.
        ta = 0.0
        tb = s
        if oz > hmax:
            if dz >= 0.0:
                continue
            ta = (hmax - oz) / dz
        if dz > 0.0:
            tb = min(tb, (hmax - oz) / dz)
        if tb <= ta:
            continue
        # The ray's end is on the surface when it meets the terrain: test just before it.
        last = tb - end_offset if tb == s else tb
        if last <= ta:
            last = 0.5 * (ta + tb)
        step = (tb - ta) / samples
        t_prev = ta
        prev = _in_shadow(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, ox + ta * dx, oy + ta * dy,
                          oz + ta * dz, sx, sy, sz, t_min, t_max)
        total = 0.0
        for j in range(1, samples + 1):
            t_cur = ta + j * step
            t_test = min(t_cur, last)
            cur = _in_shadow(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, ox + t_test * dx,
                             oy + t_test * dy, oz + t_test * dz, sx, sy, sz, t_min, t_max)
            if cur == prev:
                if cur:
                    total += t_cur - t_prev
            else:
                lo = t_prev
                hi = t_test
                for _ in range(refine):
                    mid = 0.5 * (lo + hi)
                    st = _in_shadow(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, ox + mid * dx,
                                    oy + mid * dy, oz + mid * dz, sx, sy, sz, t_min, t_max)
                    if st == prev:
                        lo = mid
                    else:
                        hi = mid
                edge = 0.5 * (lo + hi)
                if prev:
                    total += edge - t_prev
                else:
                    total += t_cur - edge
            prev = cur
            t_prev = t_cur
        out[i] = min(total, s)


def shadow_lengths(tracer: HeightfieldTracer | Terrain, origins: ArrayLike, directions: ArrayLike,
                   distances: ArrayLike, sun_direction: ArrayLike, *, samples: int = DEFAULT_SHADOW_SAMPLES,
                   refine: int = DEFAULT_REFINE) -> NDArray[np.float64]:
    """Length [m] of each view ray that lies in the terrain's shadow (ray marching with exact shadow rays).

    Parameters
    ----------
    tracer : HeightfieldTracer or Terrain
        The terrain (a tracer is built for a Terrain).
    origins : array_like, shape (3,) or (..., 3)
        Ray origins [m, ENU, heights above sea level]; one origin may be shared by all rays.
    directions : array_like, shape (..., 3)
        View directions (normalised here).
    distances : array_like, shape (...)
        Length [m] of each ray: the distance to the terrain for rays that hit it; for rays that miss, any
        finite length (the part above the highest terrain point is never shadowed and is not marched).
    sun_direction : array_like, shape (3,)
        Unit vector towards the sun; with the sun on or below the horizon every length is 0 (the Earth's own
        shadow is in the tables).
    samples : int
        Equal steps per ray (>= 1).
    refine : int
        Bisections of each step whose ends disagree (>= 0).

    Returns
    -------
    ndarray, shape (...)
        Shadowed length [m], in [0, distance].
    """
    if isinstance(tracer, Terrain):
        tracer = HeightfieldTracer(tracer)
    if not isinstance(tracer, HeightfieldTracer):
        raise InvalidParameterError(f"tracer must be a HeightfieldTracer or Terrain; got {type(tracer).__name__}")
    whole_number("samples", samples, 1, integral_floats=True)
    whole_number("refine", refine, 0, integral_floats=True)
    d = as_directions(directions)
    shape = d.shape[:-1]
    s = np.asarray(distances, dtype=float)
    try:
        s = np.broadcast_to(s, shape)
    except ValueError:
        raise InvalidParameterError(f"distances {s.shape} do not match the directions {d.shape}") from None
    if not np.all(np.isfinite(s)) or np.any(s < 0):
        raise InvalidParameterError("distances must be finite and >= 0 [m] (give a finite length for misses)")
    o = np.asarray(origins, dtype=float)
    if o.shape[-1:] != (3,) or not np.all(np.isfinite(o)):
        raise InvalidParameterError(f"ray origins must be finite ENU positions [m], shape (..., 3); got {o.shape}")
    o2 = o.reshape(1, 3) if o.ndim == 1 else np.ascontiguousarray(np.broadcast_to(o, d.shape).reshape(-1, 3))
    sun = as_directions(sun_direction).reshape(-1)
    if sun.size != 3:
        raise InvalidParameterError("sun_direction must be a single direction (3,)")
    out = np.zeros(int(np.prod(shape, dtype=np.int64)))
    if sun[2] <= 0.0 or out.size == 0:
        return out.reshape(shape)
    eps = 1e-3 * tracer.terrain.spacing
    _shadow_lengths(*tracer.trace_arguments, o2,
                    np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64),
                    np.ascontiguousarray(s.reshape(-1), dtype=np.float64), np.ascontiguousarray(sun),
                    int(samples), int(refine), eps, tracer.max_distance, eps, out)
    return out.reshape(shape)
