"""Tracking through a gridded 3D cloud field: delta tracking for free paths, ratio tracking for shadow rays.

The field (:class:`skyscatter.atmosphere.clouds.CloudField`, packed by :func:`pack_field`) is a grid of
``nx x ny x nz`` voxels of constant density ``rho`` (the extinction coefficient at the field's reference
wavelength [m^-1]) over a box whose horizontal coordinates are the planet-frame ``x`` (east) and ``y``
(north) of the tracer [m] and whose vertical coordinate is the altitude ``h = |p| - bottom_radius`` [m]: the
voxel boundaries are vertical planes ``x = const``, ``y = const`` and spheres ``|p| = const``, so that a
horizontally uniform field is an exact spherical shell. The sides are periodic (the field repeats with its
size) or open (zero density outside the box).

**Majorant grid.** The voxels are grouped into blocks of ``bx x by x bz`` voxels; each block keeps the largest
and the smallest density of its voxels (``bmax``, ``bmin``). Rays walk from block to block (a 3D DDA whose
crossings are ray-plane and ray-sphere intersections, the indices stepped exactly rather than recomputed from
rounded positions), so thin air around a dense cloud is crossed at the block's own rate, not at the cloud's.

**Free paths: decomposition + delta tracking** ([Woodcock1965]; [Kutz2017] Sec. 4-5). In a block the density
is split into the constant control ``bmin`` and the residual ``rho - bmin <= bmax - bmin``. The control's free
path is exponential (sampled exactly); the residual's by delta tracking against the residual majorant
``mu = s_max (bmax - bmin)`` with ``s_max`` the largest spectral scale ``s_i = sigma_i / rho`` of the
wavelength group, so that one majorant serves every wavelength. A tentative residual collision at density
``rho`` is real with probability ``s_h (rho - bmin) / mu`` for the hero ``h``. Homogeneous blocks (``bmax =
bmin``: a uniform layer, a column of the I3RC step cloud) have no tentative collisions at all: the free path is
exact.

**Spectral MIS.** The path weights ``f_i`` and the hero densities ``p_i`` (balance heuristic, [Veach1997]
Sec. 9.2.4; the kernels' ``f`` and ``p`` arrays, docs/montecarlo.md) are multiplied by ``exp(-s_i bmin l)`` for
each control segment of length ``l`` and by ``(mu - s_i (rho - bmin)) / mu`` at each rejected (null) residual
collision: the same factor for ``f_i`` and ``p_i``, which is ``T_i`` estimated by the null-collision integral
([Galtier2013]) for ``f`` and the probability of the hero's decisions
had ``i`` been the hero for ``p``. The collision density at a real collision is then ``s_i rho`` for every
wavelength (the kernels multiply ``p_i`` by the total extinction there).

**Shadow rays: residual ratio tracking** ([Novak2014] Sec. 4): per
wavelength ``T_i = exp(-s_i sum_blocks bmin l) prod_events (1 - s_i (rho - bmin) / mu)``, unbiased for every
wavelength with one set of tentative events. With the voxel grid as its own majorant grid (``bx = by = bz =
1``, :func:`pack_field` ``exact=True``) there are no events: the transmittance is exact (regular tracking).
A shadow ray stops once ``s_i sum bmin l > 50`` for every wavelength (``T < 2e-22``).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..jit import helper, inline
from ..vecmath import exp_lane
from .rng import next_uniform

__all__ = ["PackedField", "STOP_OPTICAL_DEPTH", "box_clip", "empty_field", "field_box_hit", "field_density",
           "field_density_at", "field_free_path", "field_transmittance", "pack_grid"]

#: Control optical depth beyond which a shadow ray counts as blocked (exp(-50) = 2e-22).
STOP_OPTICAL_DEPTH = 50.0
_INF = math.inf

# layout of the float parameters ``vf`` of a packed field
X0, Y0, R0, DX, DY, DZ, LX, LY, PRESENT, PERIODIC, R_TOP = range(11)
# layout of the integer parameters ``vi``
NX, NY, NZ, BX, BY, BZ, NBX, NBY, NBZ = range(9)


@inline
def _floor_div(a, b):
    return int(math.floor(a / b))


@inline
def _block_of(local, edges, nb, direction):
    """Block index of a local coordinate in ``[edges[0], edges[nb]]``; on a boundary the side ``direction`` points
    to (``direction >= 0`` takes the upper block)."""
    j = 0
    while j < nb - 1 and edges[j + 1] <= local:
        j += 1
    if direction < 0.0 and j > 0 and local <= edges[j]:
        j -= 1
    return j


@inline
def _radial_state(r, b, re, nbz):
    """Radial block index of radius ``r`` moving with radial velocity sign ``b``: -1 below the field, ``nbz``
    above it. A point on a boundary sphere (within ``1e-6 m + 1e-12 r``: the rounding of a radius computed from
    coordinates) belongs to the shell it moves into."""
    eps = 1e-6 + 1e-12 * r
    if r < re[0] - eps or (r <= re[0] + eps and b <= 0.0):
        return -1
    if r > re[nbz] + eps or (r >= re[nbz] - eps and b >= 0.0):
        return nbz
    j = 0
    while j < nbz - 1 and re[j + 1] <= r + eps:
        j += 1
    if b < 0.0 and r <= re[j] + eps:
        j -= 1
    elif b >= 0.0 and j < nbz - 1 and r >= re[j + 1] - eps:
        j += 1
    return j


@inline
def _outer_root(b, c, radius):
    disc = b * b - (c - radius * radius)
    return -b + math.sqrt(disc if disc > 0.0 else 0.0)


@inline
def _inner_root(b, c, radius):
    """Smaller root of ``|o + t d| = radius`` (the inward crossing), or inf if the ray misses the sphere."""
    disc = b * b - (c - radius * radius)
    if disc < 0.0:
        return _INF
    return -b - math.sqrt(disc)


@helper
def box_clip(ox, oy, dx, dy, x0, y0, lx, ly, ta, tb):
    """The part of ``[ta, tb]`` of the ray ``o + t d`` over the horizontal box ``[x0, x0 + lx] x [y0, y0 + ly]``
    (slabs of vertical planes, [m]); ``tb = -inf`` when the ray runs parallel to a side outside the box, else
    ``ta >= tb`` when it misses. Shared by the Monte Carlo's open fields and the ray march of
    :mod:`skyscatter.sky.broken_cloud_kernels`."""
    for axis in range(2):
        o = ox if axis == 0 else oy
        d = dx if axis == 0 else dy
        lo = x0 if axis == 0 else y0
        hi = lo + (lx if axis == 0 else ly)
        if d == 0.0:
            if o < lo or o > hi:
                return ta, -_INF
        else:
            t1 = (lo - o) / d
            t2 = (hi - o) / d
            if t1 > t2:
                t1, t2 = t2, t1
            ta = max(ta, t1)
            tb = min(tb, t2)
    return ta, tb


@helper
def field_box_hit(ox, oy, oz, dx, dy, dz, t_end, vf):
    """``(ta, tb)``: the part of ``[0, t_end]`` of the ray ``o + t d`` inside the field's horizontal box (all of it
    for a periodic field) and between the spheres of its bottom and top; ``ta >= tb`` when the ray misses it.
    The altitude test is the ray's distance interval to the top sphere (the bottom is crossed inside)."""
    ta = 0.0
    tb = t_end
    if vf[PERIODIC] == 0.0:
        ta, tb = box_clip(ox, oy, dx, dy, vf[X0], vf[Y0], vf[LX], vf[LY], ta, tb)
        if tb == -_INF:
            return 0.0, -1.0
    b = ox * dx + oy * dy + oz * dz
    c = ox * ox + oy * oy + oz * oz
    rt = vf[R_TOP]
    disc = b * b - (c - rt * rt)
    if disc <= 0.0:
        return 0.0, -1.0
    s = math.sqrt(disc)
    ta = max(ta, -b - s)
    tb = min(tb, -b + s)
    if ta < tb:
        # |o + t d|^2 is convex in t: the segment stays below the field if both ends do
        r0 = vf[R0]
        if (c + ta * (2.0 * b + ta) < r0 * r0) and (c + tb * (2.0 * b + tb) < r0 * r0):
            return 0.0, -1.0
    return ta, tb


@helper
def field_density(px, py, pz, vf, vi, rho, jx, jy, jz):
    """Density [m^-1 at the reference wavelength] of the voxel containing ``p``, clamped into block ``(jx, jy, jz)``
    (so that it never exceeds that block's majorant through rounding)."""
    nx = vi[NX]
    ny = vi[NY]
    nz = vi[NZ]
    ix = _floor_div(px - vf[X0], vf[DX])
    iy = _floor_div(py - vf[Y0], vf[DY])
    if vf[PERIODIC] != 0.0:
        ix %= nx
        iy %= ny
    r = math.sqrt(px * px + py * py + pz * pz)
    iz = _floor_div(r - vf[R0], vf[DZ])
    lo = jx * vi[BX]
    hi = min(nx, lo + vi[BX]) - 1
    ix = min(max(ix, lo), hi)
    lo = jy * vi[BY]
    hi = min(ny, lo + vi[BY]) - 1
    iy = min(max(iy, lo), hi)
    lo = jz * vi[BZ]
    hi = min(nz, lo + vi[BZ]) - 1
    iz = min(max(iz, lo), hi)
    return rho[ix, iy, iz]


@helper
def field_density_at(px, py, pz, vf, vi, rho):
    """Density of the voxel containing ``p`` (0 outside the field)."""
    nx = vi[NX]
    ny = vi[NY]
    nz = vi[NZ]
    ix = _floor_div(px - vf[X0], vf[DX])
    iy = _floor_div(py - vf[Y0], vf[DY])
    if vf[PERIODIC] != 0.0:
        ix %= nx
        iy %= ny
    elif ix < 0 or ix >= nx or iy < 0 or iy >= ny:
        return 0.0
    r = math.sqrt(px * px + py * py + pz * pz)
    iz = _floor_div(r - vf[R0], vf[DZ])
    if iz < 0 or iz >= nz:
        return 0.0
    return rho[ix, iy, iz]


@helper
def _start(ox, oy, oz, dx, dy, dz, t, vf, vi, xe, ye, re, state):
    """Block indices of the point ``o + t d`` moving along ``d``; ``state`` (6,) int64 gets jx, kx, jy, ky, jz and a
    flag 1 (inside the horizontal box; always for periodic fields)."""
    px = ox + t * dx
    py = oy + t * dy
    pz = oz + t * dz
    lx = px - vf[X0]
    ly = py - vf[Y0]
    kx = 0
    ky = 0
    if vf[PERIODIC] != 0.0:
        kx = _floor_div(lx, vf[LX])
        ky = _floor_div(ly, vf[LY])
        lx -= kx * vf[LX]
        ly -= ky * vf[LY]
        # a point on the period boundary moving down belongs to the previous period
        if lx <= 0.0 and dx < 0.0:
            kx -= 1
            lx += vf[LX]
        if ly <= 0.0 and dy < 0.0:
            ky -= 1
            ly += vf[LY]
    state[0] = _block_of(lx, xe, vi[NBX], dx)
    state[1] = kx
    state[2] = _block_of(ly, ye, vi[NBY], dy)
    state[3] = ky
    r = math.sqrt(px * px + py * py + pz * pz)
    state[4] = _radial_state(r, px * dx + py * dy + pz * dz, re, vi[NBZ])
    state[5] = 1


@helper
def _next_crossing(ox, oy, oz, dx, dy, dz, t, vf, vi, xe, ye, re, state):
    """Distance of the next block boundary after ``t`` and which axis it crosses (0 x, 1 y, 2 radius; -1 none)."""
    best = _INF
    axis = -1
    periodic = vf[PERIODIC] != 0.0
    # a periodic axis of one block never changes block: its crossings are skipped (horizontally uniform layers)
    if dx != 0.0 and not (periodic and vi[NBX] == 1):
        jx = state[0]
        base = vf[X0] + state[1] * vf[LX]
        edge = base + (xe[jx + 1] if dx > 0.0 else xe[jx])
        tx = (edge - ox) / dx
        if tx < best:
            best = tx
            axis = 0
    if dy != 0.0 and not (periodic and vi[NBY] == 1):
        jy = state[2]
        base = vf[Y0] + state[3] * vf[LY]
        edge = base + (ye[jy + 1] if dy > 0.0 else ye[jy])
        ty = (edge - oy) / dy
        if ty < best:
            best = ty
            axis = 1
    b = ox * dx + oy * dy + oz * dz
    c = ox * ox + oy * oy + oz * oz
    jz = state[4]
    nbz = vi[NBZ]
    tr = _INF
    if jz >= 0:
        ti = _inner_root(b, c, re[jz])
        if ti > t:
            tr = ti
    if jz < nbz:
        to = _outer_root(b, c, re[jz + 1])
        if to > t and to < tr:
            tr = to
    if tr < best:
        best = tr
        axis = 2
    if best < t:
        best = t
    return best, axis


@helper
def _step(ox, oy, oz, dx, dy, dz, t, axis, vf, vi, re, state):
    """Move ``state`` across the boundary on ``axis`` at distance ``t``; returns False when the ray leaves an open
    field's box."""
    if axis == 0:
        if dx > 0.0:
            state[0] += 1
            if state[0] >= vi[NBX]:
                if vf[PERIODIC] == 0.0:
                    return False
                state[0] = 0
                state[1] += 1
        else:
            state[0] -= 1
            if state[0] < 0:
                if vf[PERIODIC] == 0.0:
                    return False
                state[0] = vi[NBX] - 1
                state[1] -= 1
    elif axis == 1:
        if dy > 0.0:
            state[2] += 1
            if state[2] >= vi[NBY]:
                if vf[PERIODIC] == 0.0:
                    return False
                state[2] = 0
                state[3] += 1
        else:
            state[2] -= 1
            if state[2] < 0:
                if vf[PERIODIC] == 0.0:
                    return False
                state[2] = vi[NBY] - 1
                state[3] -= 1
    else:
        # inward crossing of the shell's lower sphere or outward crossing of its upper one
        b = ox * dx + oy * dy + oz * dz
        jz = state[4]
        if jz >= 0:
            c = ox * ox + oy * oy + oz * oz
            if t == _inner_root(b, c, re[jz]):
                state[4] = jz - 1
                return True
        state[4] = jz + 1
    return True


@helper
def field_free_path(ox, oy, oz, dx, dy, dz, t_end, hero, s, smax, vf, vi, rho, bmax, bmin, xe, ye, re, f, p, st,
                    state):
    """Free path of the hero through the field along ``o + t d``, ``0 <= t <= t_end`` [m] (module docstring).

    ``s`` (n,) spectral scales (extinction [m^-1] per unit density) of the group, ``smax`` their maximum; ``f`` and
    ``p`` (n,) are multiplied by the control transmittances and null-collision factors up to the returned
    distance; ``st`` is the random state, ``state`` (6,) int64 scratch. Returns ``(t, collided, rho)``: the
    distance of the first real collision and the density there, or ``(t_end, False, 0)``.
    """
    ta, tb = field_box_hit(ox, oy, oz, dx, dy, dz, t_end, vf)
    if ta >= tb:
        return t_end, False, 0.0
    n = s.shape[0]
    sh = s[hero]
    t = ta
    _start(ox, oy, oz, dx, dy, dz, t, vf, vi, xe, ye, re, state)
    nbz = vi[NBZ]
    for _ in range(10_000_000):
        tn, axis = _next_crossing(ox, oy, oz, dx, dy, dz, t, vf, vi, xe, ye, re, state)
        if tn >= tb:
            tn = tb
            axis = -1
        jx = state[0]
        jy = state[2]
        jz = state[4]
        if 0 <= jz < nbz:
            big = bmax[jx, jy, jz]
            if big > 0.0:
                small = bmin[jx, jy, jz]
                tc = _INF
                if small > 0.0 and sh > 0.0:
                    tc = t - math.log1p(-next_uniform(st)) / (sh * small)
                tcut = tc if tc < tn else tn
                mu = smax * (big - small)
                if mu > 0.0:
                    tt = t
                    while True:
                        tt -= math.log1p(-next_uniform(st)) / mu
                        if tt >= tcut:
                            break
                        r = field_density(ox + tt * dx, oy + tt * dy, oz + tt * dz, vf, vi, rho, jx, jy, jz)
                        if next_uniform(st) * mu < sh * (r - small):
                            if small > 0.0:
                                for i in range(n):
                                    e = exp_lane(-s[i] * small * (tt - t))
                                    f[i] *= e
                                    p[i] *= e
                            return tt, True, r
                        for i in range(n):
                            w = 1.0 - s[i] * (r - small) / mu
                            f[i] *= w
                            p[i] *= w
                if small > 0.0:
                    for i in range(n):
                        e = exp_lane(-s[i] * small * (tcut - t))
                        f[i] *= e
                        p[i] *= e
                if tc < tn:
                    r = field_density(ox + tc * dx, oy + tc * dy, oz + tc * dz, vf, vi, rho, jx, jy, jz)
                    return tc, True, r
        if axis < 0:
            break
        t = tn
        if not _step(ox, oy, oz, dx, dy, dz, t, axis, vf, vi, re, state):
            break
    return t_end, False, 0.0


@helper
def field_transmittance(ox, oy, oz, dx, dy, dz, t_end, s, smax, smin, vf, vi, rho, bmax, bmin, xe, ye, re, tr,
                        st, state):
    """Transmittance of the field along ``o + t d``, ``0 <= t <= t_end`` [m], per wavelength into ``tr`` (n,):
    residual ratio tracking (module docstring; exact for a grid packed with ``exact=True``). ``s`` (n,) spectral
    scales with maximum ``smax`` and minimum ``smin``; ``st`` random state; ``state`` (6,) int64 scratch."""
    n = s.shape[0]
    for i in range(n):
        tr[i] = 1.0
    ta, tb = field_box_hit(ox, oy, oz, dx, dy, dz, t_end, vf)
    if ta >= tb:
        return
    t = ta
    _start(ox, oy, oz, dx, dy, dz, t, vf, vi, xe, ye, re, state)
    nbz = vi[NBZ]
    column = 0.0
    for _ in range(10_000_000):
        tn, axis = _next_crossing(ox, oy, oz, dx, dy, dz, t, vf, vi, xe, ye, re, state)
        if tn >= tb:
            tn = tb
            axis = -1
        jx = state[0]
        jy = state[2]
        jz = state[4]
        if 0 <= jz < nbz:
            big = bmax[jx, jy, jz]
            if big > 0.0:
                small = bmin[jx, jy, jz]
                column += small * (tn - t)
                if smin * column > STOP_OPTICAL_DEPTH:
                    for i in range(n):
                        tr[i] = 0.0
                    return
                mu = smax * (big - small)
                if mu > 0.0:
                    tt = t
                    while True:
                        tt -= math.log1p(-next_uniform(st)) / mu
                        if tt >= tn:
                            break
                        r = field_density(ox + tt * dx, oy + tt * dy, oz + tt * dz, vf, vi, rho, jx, jy, jz)
                        wmax = 0.0
                        for i in range(n):
                            tr[i] *= 1.0 - s[i] * (r - small) / mu
                            if tr[i] > wmax:
                                wmax = tr[i]
                        if wmax < 0.01:
                            # Russian roulette on the ratio-tracking estimate ([Novak2014] Sec. 4.2)
                            if next_uniform(st) >= 0.5:
                                for i in range(n):
                                    tr[i] = 0.0
                                return
                            for i in range(n):
                                tr[i] *= 2.0
        if axis < 0:
            break
        t = tn
        if not _step(ox, oy, oz, dx, dy, dz, t, axis, vf, vi, re, state):
            break
    for i in range(n):
        tr[i] *= exp_lane(-s[i] * column)


# --------------------------------------------------------------------------------------------- packing


class PackedField(NamedTuple):
    """A cloud field's geometry, densities and majorant grid as the arrays the kernels take.

    ``vf`` (11,) float64 and ``vi`` (9,) int64 parameters (layout: the module constants ``X0 ... R_TOP`` and ``NX
    ... NBZ``); ``rho`` (nx, ny, nz) densities [m^-1 at the reference wavelength]; ``bmax``, ``bmin`` (NBX, NBY,
    NBZ) block majorants and minorants; ``xe`` (NBX + 1,), ``ye`` (NBY + 1,) block boundaries [m] from the box's
    corner; ``re`` (NBZ + 1,) radii [m] of the block boundary spheres.
    """

    vf: NDArray[np.float64]
    vi: NDArray[np.int64]
    rho: NDArray[np.float64]
    bmax: NDArray[np.float64]
    bmin: NDArray[np.float64]
    xe: NDArray[np.float64]
    ye: NDArray[np.float64]
    re: NDArray[np.float64]

    @property
    def present(self) -> bool:
        return bool(self.vf[PRESENT] != 0.0)


#: Default block edge of the majorant grid [voxels].
DEFAULT_BLOCK = 8


def _block_reduce(rho: NDArray[np.float64], block: tuple[int, int, int]) -> tuple[NDArray[np.float64],
                                                                                 NDArray[np.float64]]:
    nx, ny, nz = rho.shape
    bx, by, bz = block
    nbx, nby, nbz = -(-nx // bx), -(-ny // by), -(-nz // bz)
    pad = np.full((nbx * bx, nby * by, nbz * bz), np.nan)
    pad[:nx, :ny, :nz] = rho
    blocks = pad.reshape(nbx, bx, nby, by, nbz, bz)
    return (np.ascontiguousarray(np.nanmax(blocks, axis=(1, 3, 5))),
            np.ascontiguousarray(np.nanmin(blocks, axis=(1, 3, 5))))


def _edges(n: int, b: int, step: float) -> NDArray[np.float64]:
    e = np.minimum(np.arange(0, n + b, b), n)
    e = np.unique(e).astype(float) * step
    e[-1] = n * step
    return np.ascontiguousarray(e)


def pack_grid(extinction: NDArray[np.float64], size: tuple[float, float], origin: tuple[float, float], base: float,
              top: float, periodic: bool, bottom_radius: float, block: Any = None, exact: bool = False) -> PackedField:
    """Pack a voxel grid for the kernels (:class:`PackedField`).

    ``block`` is the majorant block edge in voxels (one number or (bx, by, bz); default :data:`DEFAULT_BLOCK`,
    at most the grid's size per axis); ``exact=True`` makes every voxel its own block, so that
    :func:`field_transmittance` is exact and :func:`field_free_path` samples without null collisions.
    """
    rho = np.ascontiguousarray(extinction, dtype=float)
    nx, ny, nz = rho.shape
    if exact:
        bx = by = bz = 1
    else:
        b = np.atleast_1d(np.asarray(DEFAULT_BLOCK if block is None else block, dtype=np.int64))
        b = np.repeat(b, 3) if b.size == 1 else b
        bx, by, bz = (int(min(max(1, v), n)) for v, n in zip(b, (nx, ny, nz), strict=True))
    if exact:
        bmax = rho.copy()
        bmin = rho.copy()
    else:
        bmax, bmin = _block_reduce(rho, (bx, by, bz))
    sx, sy = size
    dx, dy, dz = sx / nx, sy / ny, (top - base) / nz
    xe, ye = _edges(nx, bx, dx), _edges(ny, by, dy)
    r0 = bottom_radius + base
    re = np.ascontiguousarray(r0 + _edges(nz, bz, dz))
    re[-1] = bottom_radius + top
    vf = np.zeros(11)
    vf[[X0, Y0, R0, DX, DY, DZ, LX, LY, PRESENT, PERIODIC, R_TOP]] = (
        origin[0], origin[1], r0, dx, dy, dz, sx, sy, 1.0, 1.0 if periodic else 0.0, bottom_radius + top)
    vi = np.array([nx, ny, nz, bx, by, bz, bmax.shape[0], bmax.shape[1], bmax.shape[2]], dtype=np.int64)
    return PackedField(vf, vi, rho, bmax, bmin, xe, ye, re)


def empty_field() -> PackedField:
    """The arrays of "no cloud field" (``present`` False)."""
    z = np.zeros((1, 1, 1))
    one = np.array([0.0, 1.0])
    vf = np.zeros(11)
    vf[[DX, DY, DZ, LX, LY]] = 1.0
    return PackedField(vf, np.ones(9, dtype=np.int64), z, z.copy(), z.copy(), one, one.copy(), one.copy() + 1.0)
