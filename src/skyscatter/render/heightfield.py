"""Ray-heightfield intersection and shadow rays, compiled with numba.

The surface of each grid cell is the bilinear patch through its four corner heights, so along a ray the
height difference ``h(x(t), y(t)) - z(t)`` is a quadratic in ``t`` and each cell is intersected exactly.
Rays walk the grid with a two-level digital differential analyser (Amanatides & Woo 1987): an outer walk over
blocks of ``block x block`` cells that skips every block whose highest sample is below the ray, and an inner
walk over the cells of the blocks the ray may touch. Periodic terrains are walked in unbounded cell
coordinates (indices wrap); a finite grid is surrounded by a flat plain at ``Terrain.base_height``.

Distances are along unit directions, in metres.

Public tracer API: :class:`HeightfieldTracer` (``intersect``, ``occluded``, ``shadow_lengths``) for arrays of
rays, and :func:`trace_ray`, the numba-compiled single-ray kernel, for other compiled loops (it takes
:attr:`HeightfieldTracer.trace_arguments` followed by the ray), as :mod:`skyscatter.render.shafts` does.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..aerial.base import DEFAULT_REFINE, DEFAULT_SHADOW_SAMPLES, ShadowCaster
from ..conventions import as_directions
from ..errors import InvalidParameterError
from ..jit import helper, inline, parallel_kernel
from .terrain import Terrain

__all__ = ["DEFAULT_MAX_DISTANCE", "HeightfieldTracer", "trace_ray"]

#: Longest ray [m] followed over a periodic terrain (beyond it a near-horizontal ray counts as a miss).
DEFAULT_MAX_DISTANCE = 500_000.0

_INF = np.inf
#: Largest |x|, |y| [m] of a ray origin over a finite grid (beyond it grid indices lose their meaning).
_MAX_OFFSET = 1e12


@inline
def _cell_hit(h, ix, iy, wrap, nx, ny, gx, gy, oz, dgx, dgy, dz, tc0, tc1):
    """First t in [tc0, tc1] where the ray meets the bilinear patch of cell (ix, iy), or inf."""
    if wrap:
        i0 = ix % nx
        j0 = iy % ny
        i1 = (i0 + 1) % nx
        j1 = (j0 + 1) % ny
    else:
        i0 = ix
        j0 = iy
        i1 = ix + 1
        j1 = iy + 1
    h00 = h[j0, i0]
    h10 = h[j0, i1]
    h01 = h[j1, i0]
    h11 = h[j1, i1]
    # The ray's lowest point over the cell is above the highest corner: no hit (cheap early out).
    zlo = oz + dz * (tc1 if dz < 0.0 else tc0)
    if zlo > max(max(h00, h10), max(h01, h11)):
        return _INF
    b = h10 - h00
    c = h01 - h00
    d = h00 - h10 - h01 + h11
    u0 = gx + tc0 * dgx - ix
    v0 = gy + tc0 * dgy - iy
    z0 = oz + tc0 * dz
    cc = h00 + b * u0 + c * v0 + d * u0 * v0 - z0
    if cc >= 0.0:
        return tc0
    aa = d * dgx * dgy
    bb = b * dgx + c * dgy + d * (u0 * dgy + v0 * dgx) - dz
    length = tc1 - tc0
    disc = bb * bb - 4.0 * aa * cc
    if disc < 0.0:
        return _INF
    sq = math.sqrt(disc)
    q = -0.5 * (bb + (sq if bb >= 0.0 else -sq))
    best = _INF
    if q != 0.0:
        r = cc / q
        if 0.0 <= r <= length:
            best = r
    if aa != 0.0:
        r = q / aa
        if 0.0 <= r <= length and r < best:
            best = r
    if best == _INF:
        return _INF
    return tc0 + best


# The walkers never allocate: helpers without numba's runtime (skyscatter.jit, docs/architecture.md); the light
# shafts call them once per shadow ray, one ray per sample.
@helper
def _walk_cells(h, wrap, nx, ny, ncx, ncy, block, bx, by, gx, gy, oz, dgx, dgy, dz, t0, t1):
    """Walk the cells of block (bx, by) between t0 and t1; first hit or inf."""
    tm = t0
    px = gx + tm * dgx
    py = gy + tm * dgy
    lox = bx * block
    loy = by * block
    hix = lox + block - 1
    hiy = loy + block - 1
    if not wrap:
        hix = min(hix, ncx - 1)
        hiy = min(hiy, ncy - 1)
    ix = min(max(int(math.floor(px)), lox), hix)
    iy = min(max(int(math.floor(py)), loy), hiy)
    if dgx > 0.0:
        tnx = (ix + 1 - gx) / dgx
        tdx = 1.0 / dgx
        sx = 1
    elif dgx < 0.0:
        tnx = (ix - gx) / dgx
        tdx = -1.0 / dgx
        sx = -1
    else:
        tnx = _INF
        tdx = _INF
        sx = 0
    if dgy > 0.0:
        tny = (iy + 1 - gy) / dgy
        tdy = 1.0 / dgy
        sy = 1
    elif dgy < 0.0:
        tny = (iy - gy) / dgy
        tdy = -1.0 / dgy
        sy = -1
    else:
        tny = _INF
        tdy = _INF
        sy = 0
    tc = t0
    while True:
        tn = min(min(tnx, tny), t1)
        if tn < tc:
            tn = tc
        t = _cell_hit(h, ix, iy, wrap, nx, ny, gx, gy, oz, dgx, dgy, dz, tc, tn)
        if t != _INF:
            return t
        if tn >= t1:
            return _INF
        if tnx <= tny:
            ix += sx
            tc = tnx
            tnx += tdx
        else:
            iy += sy
            tc = tny
            tny += tdy
        if ix < lox or ix > hix or iy < loy or iy > hiy:
            return _INF


@helper
def _walk_grid(h, bmax, wrap, block, gx, gy, oz, dgx, dgy, dz, ta, tb):
    """Two-level walk between ta and tb (grid coordinates in cells, t in metres); first hit or inf."""
    ny, nx = h.shape
    nby, nbx = bmax.shape
    if wrap:
        ncx = nx
        ncy = ny
    else:
        ncx = nx - 1
        ncy = ny - 1
    px = gx + ta * dgx
    py = gy + ta * dgy
    bx = int(math.floor(px / block))
    by = int(math.floor(py / block))
    if not wrap:
        bx = min(max(bx, 0), nbx - 1)
        by = min(max(by, 0), nby - 1)
    if dgx > 0.0:
        tnx = ((bx + 1) * block - gx) / dgx
        tdx = block / dgx
        sx = 1
    elif dgx < 0.0:
        tnx = (bx * block - gx) / dgx
        tdx = -block / dgx
        sx = -1
    else:
        tnx = _INF
        tdx = _INF
        sx = 0
    if dgy > 0.0:
        tny = ((by + 1) * block - gy) / dgy
        tdy = block / dgy
        sy = 1
    elif dgy < 0.0:
        tny = (by * block - gy) / dgy
        tdy = -block / dgy
        sy = -1
    else:
        tny = _INF
        tdy = _INF
        sy = 0
    t = ta
    while True:
        t1 = min(min(tnx, tny), tb)
        if t1 < t:
            t1 = t
        zlo = oz + dz * (t1 if dz < 0.0 else t)
        if wrap:
            top = bmax[by % nby, bx % nbx]
        else:
            top = bmax[by, bx]
        if zlo <= top:
            hit = _walk_cells(h, wrap, nx, ny, ncx, ncy, block, bx, by, gx, gy, oz, dgx, dgy, dz, t, t1)
            if hit != _INF:
                return hit
        if t1 >= tb:
            return _INF
        if tnx <= tny:
            bx += sx
            t = tnx
            tnx += tdx
        else:
            by += sy
            t = tny
            tny += tdy
        if not wrap and (bx < 0 or bx >= nbx or by < 0 or by >= nby):
            return _INF


@helper
def trace_ray(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, ox, oy, oz, dx, dy, dz, tmin, tmax):
    """Distance [m] along one ray to the first point of the terrain surface, or ``inf`` (numba-compiled).

    Parameters
    ----------
    h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax
        The terrain as the tracer holds it: :attr:`HeightfieldTracer.trace_arguments` (heights [m], the
        highest height of each skip block [m], periodic or not, block size [cells], sample spacing [m], grid
        origin [m], the plain's height [m] and the lowest and highest height anywhere [m]).
    ox, oy, oz : float
        Ray origin [m, ENU].
    dx, dy, dz : float
        Unit ray direction (ENU).
    tmin, tmax : float
        Search interval [m] along the ray.

    Returns
    -------
    float
        Distance [m] of the first hit in [tmin, tmax], or ``inf`` when the ray misses. Callable from other
        numba functions (nopython mode) and from Python.
    """
    ta = tmin
    tb = tmax
    # Clip to the slab hmin <= z <= hmax that holds all terrain.
    if dz > 0.0:
        if oz > hmax:
            return _INF
        tb = min(tb, (hmax - oz) / dz)
    elif dz < 0.0:
        if oz > hmax:
            ta = max(ta, (hmax - oz) / dz)
        tb = min(tb, (hmin - oz) / dz + 1e-6)
    elif oz > hmax:
        return _INF
    if ta > tb:
        return _INF
    ny, nx = h.shape
    gx = (ox - x0) / spacing
    gy = (oy - y0) / spacing
    dgx = dx / spacing
    dgy = dy / spacing
    if wrap:
        return _walk_grid(h, bmax, True, block, gx, gy, oz, dgx, dgy, dz, ta, tb)
    # Finite grid inside a plain: the ray's line meets the grid rectangle in one interval [t_in, t_out].
    t_in = -_INF
    t_out = _INF
    for g, dg, n in ((gx, dgx, nx - 1), (gy, dgy, ny - 1)):
        if dg != 0.0:
            a = (0.0 - g) / dg
            b = (n - g) / dg
            if a > b:
                a, b = b, a
            t_in = max(t_in, a)
            t_out = min(t_out, b)
        elif g < 0.0 or g > n:
            t_in = _INF
            t_out = -_INF
    t_plane = (base - oz) / dz if dz < 0.0 else _INF
    lo = max(ta, t_in)
    hi = min(tb, t_out)
    if lo <= hi:
        if t_plane < lo and t_plane >= tmin:
            return t_plane
        hit = _walk_grid(h, bmax, False, block, gx, gy, oz, dgx, dgy, dz, lo, hi)
        if hit != _INF:
            return hit
        if t_plane > t_out and t_plane <= tmax:
            return t_plane
        return _INF
    if tmin <= t_plane <= tmax:
        return t_plane
    return _INF


@parallel_kernel
def _trace_many(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax, origins, dirs, tmin, tmax, out):
    n = dirs.shape[0]
    stride = 0 if origins.shape[0] == 1 else 1
    for i in numba.prange(n):
        k = i * stride
        out[i] = trace_ray(h, bmax, wrap, block, spacing, x0, y0, base, hmin, hmax,
                        origins[k, 0], origins[k, 1], origins[k, 2], dirs[i, 0], dirs[i, 1], dirs[i, 2],
                        tmin, tmax)


def _block_maxima(terrain: Terrain, block: int) -> NDArray[np.float64]:
    h = terrain.heights
    if terrain.wrap:
        # cell (i, j) spans samples i..i+1 (mod n)
        hp = np.concatenate([h, h[:1]], axis=0)
        hp = np.concatenate([hp, hp[:, :1]], axis=1)
    else:
        hp = h
    cell = np.maximum(np.maximum(hp[:-1, :-1], hp[1:, :-1]), np.maximum(hp[:-1, 1:], hp[1:, 1:]))
    ncy, ncx = cell.shape
    nby, nbx = -(-ncy // block), -(-ncx // block)
    padded = np.full((nby * block, nbx * block), -np.inf)
    padded[:ncy, :ncx] = cell
    return np.ascontiguousarray(padded.reshape(nby, block, nbx, block).max(axis=(1, 3)))


def _choose_block(terrain: Terrain, block: int | None) -> int:
    if block is not None:
        if int(block) != block or block < 1:
            raise InvalidParameterError(f"block must be a whole number of cells >= 1; got {block!r}")
        block = int(block)
        if terrain.wrap and (terrain.shape[0] % block or terrain.shape[1] % block):
            raise InvalidParameterError(
                f"for a periodic terrain the block size ({block}) must divide the grid size {terrain.shape}"
            )
        return block
    for b in (16, 8, 4, 2, 1):
        if not terrain.wrap or (terrain.shape[0] % b == 0 and terrain.shape[1] % b == 0):
            return b
    return 1  # pragma: no cover


class HeightfieldTracer(ShadowCaster):
    """Exact ray casting against a :class:`~skyscatter.render.terrain.Terrain` (bilinear cells).

    Also the terrain's :class:`~skyscatter.aerial.base.ShadowCaster` for light shafts (:meth:`shadow_lengths`).

    Parameters
    ----------
    terrain : Terrain
        The heightfield.
    block : int, optional
        Cells per side of the skip blocks (default 16, or the largest of 16, 8, 4, 2 dividing a periodic grid).
    max_distance : float
        Longest ray [m] followed (mostly matters over periodic terrain).
    """

    def __init__(self, terrain: Terrain, *, block: int | None = None,
                 max_distance: float = DEFAULT_MAX_DISTANCE) -> None:
        if not (max_distance > 0):
            raise InvalidParameterError(f"max_distance must be a positive length [m]; got {max_distance!r}")
        self.terrain = terrain
        self.block = _choose_block(terrain, block)
        self.max_distance = float(max_distance)
        self._bmax = _block_maxima(terrain, self.block)
        self._hmin, self._hmax = terrain.height_range

    @property
    def trace_arguments(self) -> tuple:
        """The leading arguments of :func:`trace_ray` for this terrain: ``(heights, block_maxima, wrap, block,
        spacing, x0, y0, base_height, lowest, highest)`` (arrays [m], booleans, cells, metres)."""
        t = self.terrain
        return (t.heights, self._bmax, t.wrap, self.block, t.spacing, t.origin[0], t.origin[1],
                float(t.base_height), self._hmin, self._hmax)

    def _run(self, origins: ArrayLike, directions: ArrayLike, t_min: float, t_max: float | None) -> NDArray:
        d = as_directions(directions)
        shape = d.shape[:-1]
        d2 = np.ascontiguousarray(d.reshape(-1, 3), dtype=np.float64)
        o = np.asarray(origins, dtype=np.float64)
        if o.shape[-1:] != (3,) or not np.all(np.isfinite(o)):
            raise InvalidParameterError(f"ray origins must be finite ENU positions [m], shape (..., 3); got {o.shape}")
        if o.ndim == 1:
            o2 = o.reshape(1, 3).copy()
        else:
            o2 = np.array(np.broadcast_to(o, d.shape).reshape(-1, 3))
        t = self.terrain
        if t.wrap:
            # Shift the origins into the first period: the same rays, but the walk's cell and block indices
            # stay small (huge coordinates would overflow them and stall the walk).
            ny, nx = t.shape
            for k, n in ((0, nx), (1, ny)):
                period = n * t.spacing
                o2[:, k] = t.origin[k] + np.mod(o2[:, k] - t.origin[k], period)
        elif np.max(np.abs(o2[:, :2])) > _MAX_OFFSET:
            raise InvalidParameterError(
                f"ray origins must be within +-{_MAX_OFFSET:g} m of the ENU origin horizontally; got "
                f"{np.max(np.abs(o2[:, :2])):.6g} m"
            )
        t_max = self.max_distance if t_max is None else float(t_max)
        out = np.empty(d2.shape[0])
        _trace_many(*self.trace_arguments, o2, d2, float(t_min), t_max, out)
        return out.reshape(shape)

    def intersect(self, origins: ArrayLike, directions: ArrayLike, *, t_min: float = 0.0,
                  t_max: float | None = None) -> NDArray[np.float64]:
        """Distance [m] along each ray to the first terrain point, ``inf`` where the ray misses.

        Parameters
        ----------
        origins : array_like, shape (3,) or (..., 3)
            Ray origins [m, ENU]; one origin is shared by all rays.
        directions : array_like, shape (..., 3)
            Ray directions (normalised here).
        t_min, t_max : float
            Search interval [m] along the ray; ``t_max`` defaults to ``max_distance``.
        """
        return self._run(origins, directions, t_min, t_max)

    def occluded(self, origins: ArrayLike, directions: ArrayLike, *, t_min: float | None = None,
                 t_max: float | None = None) -> NDArray[np.bool_]:
        """True where a ray from ``origins`` towards ``directions`` meets the terrain (shadow rays).

        ``t_min`` [m] defaults to 1e-3 of the grid spacing, so a ray leaving a surface point does not hit
        the patch it starts on.
        """
        if t_min is None:
            t_min = 1e-3 * self.terrain.spacing
        return np.isfinite(self._run(origins, directions, t_min, t_max))

    def shadow_lengths(self, origins: ArrayLike, directions: ArrayLike, distances: ArrayLike,
                       sun_direction: ArrayLike, *, samples: int = DEFAULT_SHADOW_SAMPLES,
                       refine: int = DEFAULT_REFINE) -> NDArray[np.float64]:
        """Length [m] of each ray that lies in the terrain's shadow: :func:`skyscatter.render.shafts.shadow_lengths`."""
        from .shafts import shadow_lengths

        return shadow_lengths(self, origins, directions, distances, sun_direction, samples=samples, refine=refine)
