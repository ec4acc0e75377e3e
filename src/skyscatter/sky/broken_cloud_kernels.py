"""Numba kernels of the ``broken-cloud`` sky (:mod:`.broken_cloud`): the sun's shadow volume of a cloud field and
the ray march of view rays through it.

Geometry (the Monte Carlo's, :mod:`skyscatter.montecarlo.tracking`): planet-centred frame, the observer on the
+z axis; a point ``p`` lies in voxel ``ix = floor((p_x - x0) / dx)``, ``iy = floor((p_y - y0) / dy)`` (wrapped
when the field is periodic) and ``iz = floor((|p| - r_base) / dz)``: vertical planes and spheres, the field's
density constant per voxel. Imported on first use (numba compiles on import when the cache is cold).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..jit import helper, kernel, parallel_kernel
from ..montecarlo.tracking import field_transmittance

__all__ = ["march_rays", "shadow_volume", "ground_shadow"]

# layout of the float geometry ``gf``
G_X0, G_Y0, G_DX, G_DY, G_DZ, G_LX, G_LY, G_RBASE, G_RTOP, G_RGROUND, G_PERIODIC = range(11)
# layout of the march parameters ``mp``
M_A, M_B, M_C, M_D, M_STEP, M_LOD, M_TMIN = range(7)
#: View transmittance (every wavelength) below which a ray's march stops: what lies behind adds < 1e-3 of it.
T_STOP = 1e-3


@helper
def _sphere_roots(b, c, radius):
    """Roots ``t`` of ``|o + t d| = radius`` for ``b = o.d``, ``c = |o|^2``; (inf, -inf) when it misses."""
    disc = b * b - (c - radius * radius)
    if disc < 0.0:
        return math.inf, -math.inf
    s = math.sqrt(disc)
    return -b - s, -b + s


@helper
def _voxel(px, py, pz, gf, nx, ny, nz):
    """Voxel indices of ``p`` and whether it is inside the field."""
    ix = int(math.floor((px - gf[G_X0]) / gf[G_DX]))
    iy = int(math.floor((py - gf[G_Y0]) / gf[G_DY]))
    if gf[G_PERIODIC] != 0.0:
        ix %= nx
        iy %= ny
    elif ix < 0 or ix >= nx or iy < 0 or iy >= ny:
        return 0, 0, 0, False
    r = math.sqrt(px * px + py * py + pz * pz)
    iz = int(math.floor((r - gf[G_RBASE]) / gf[G_DZ]))
    if iz < 0 or iz >= nz:
        return 0, 0, 0, False
    return ix, iy, iz, True


@helper
def _trilinear(vol, fx, fy, fz, periodic):
    """Trilinear interpolation of a cell-centred volume at continuous voxel coordinates ``(fx, fy, fz)`` (voxel
    ``i`` spans ``[i, i + 1)``): periodic or clamped in x and y, clamped in z (a horizontally uniform field
    stays uniform up to its faces)."""
    nx, ny, nz = vol.shape
    u = fx - 0.5
    v = fy - 0.5
    w = min(max(fz - 0.5, 0.0), nz - 1.0)
    i0 = int(math.floor(u))
    j0 = int(math.floor(v))
    k0 = min(int(math.floor(w)), nz - 2) if nz > 1 else 0
    fu = u - i0
    fv = v - j0
    fw = w - k0 if nz > 1 else 0.0
    i1 = i0 + 1
    j1 = j0 + 1
    if periodic:
        i0 %= nx
        i1 %= nx
        j0 %= ny
        j1 %= ny
    else:
        if i0 < 0:
            i0 = 0
            fu = 0.0
        if i1 > nx - 1:
            i1 = nx - 1
        if i0 > nx - 1:
            i0 = nx - 1
        if j0 < 0:
            j0 = 0
            fv = 0.0
        if j1 > ny - 1:
            j1 = ny - 1
        if j0 > ny - 1:
            j0 = ny - 1
    k1 = k0 + 1 if nz > 1 else 0
    c00 = vol[i0, j0, k0] * (1.0 - fu) + vol[i1, j0, k0] * fu
    c10 = vol[i0, j1, k0] * (1.0 - fu) + vol[i1, j1, k0] * fu
    c01 = vol[i0, j0, k1] * (1.0 - fu) + vol[i1, j0, k1] * fu
    c11 = vol[i0, j1, k1] * (1.0 - fu) + vol[i1, j1, k1] * fu
    c0 = c00 * (1.0 - fv) + c10 * fv
    c1 = c01 * (1.0 - fv) + c11 * fv
    return c0 * (1.0 - fw) + c1 * fw


@kernel
def shadow_volume(gf, vf, vi, rho, bmax, bmin, xe, ye, re, sun, out, start, stop):
    """Optical depth at the reference wavelength from each voxel centre to the sun through the field, for voxels
    ``start..stop`` of the flattened grid (called through :func:`skyscatter.precomputed.parallel.parallel_for`)
    into ``out`` (nx, ny, nz): the exact integral of the voxel-constant
    field along the sun ray (:func:`skyscatter.montecarlo.tracking.field_transmittance` on a grid packed
    ``exact=True``: regular tracking, no random events), capped at 50 (``T < 2e-22``)."""
    nx, ny, nz = rho.shape
    s = np.ones(1)
    tr = np.ones(1)
    st = np.zeros(1, dtype=np.uint64)
    state = np.zeros(6, dtype=np.int64)
    for flat in range(start, stop):
        i = flat // (ny * nz)
        j = (flat // nz) % ny
        k = flat % nz
        x = gf[G_X0] + (i + 0.5) * gf[G_DX]
        y = gf[G_Y0] + (j + 0.5) * gf[G_DY]
        r = gf[G_RBASE] + (k + 0.5) * gf[G_DZ]
        z = math.sqrt(max(r * r - x * x - y * y, 0.0))
        field_transmittance(x, y, z, sun[0], sun[1], sun[2], 1e12, s, 1.0, 1.0, vf, vi, rho, bmax, bmin, xe, ye,
                            re, tr, st, state)
        out[i, j, k] = -math.log(tr[0]) if tr[0] > 1.9e-22 else 50.0


@kernel
def ground_shadow(points, vf, vi, rho, bmax, bmin, xe, ye, re, sun, out, start, stop):
    """Optical depth at the reference wavelength from ``points`` (n, 3) [m, planet frame] to the sun through the
    field (as :func:`shadow_volume`), into ``out`` (n,)."""
    s = np.ones(1)
    tr = np.ones(1)
    st = np.zeros(1, dtype=np.uint64)
    state = np.zeros(6, dtype=np.int64)
    for n in range(start, stop):
        field_transmittance(points[n, 0], points[n, 1], points[n, 2], sun[0], sun[1], sun[2], 1e12, s, 1.0, 1.0,
                            vf, vi, rho, bmax, bmin, xe, ye, re, tr, st, state)
        out[n] = -math.log(tr[0]) if tr[0] > 1.9e-22 else 50.0


@helper
def _block_exit(px, py, pz, dx, dy, dz, ix, iy, iz, gf, bsize, nx, ny, nz):
    """Distance [m] along ``d`` from ``p`` to the boundary of the block of ``bsize`` voxels holding voxel
    ``(ix, iy, iz)``: exact for the vertical planes; for the spheres the altitude's rate ``p.d / |p|`` (the
    curvature of a few-hundred-metre step is below a millimetre)."""
    t = math.inf
    bx = (ix // bsize) * bsize
    by = (iy // bsize) * bsize
    bz = (iz // bsize) * bsize
    # position inside the (periodic) domain
    xl = px - gf[G_X0]
    yl = py - gf[G_Y0]
    if gf[G_PERIODIC] != 0.0:
        xl -= math.floor(xl / gf[G_LX]) * gf[G_LX]
        yl -= math.floor(yl / gf[G_LY]) * gf[G_LY]
    if dx > 0.0:
        t = min(t, (min(bx + bsize, nx) * gf[G_DX] - xl) / dx)
    elif dx < 0.0:
        t = min(t, (bx * gf[G_DX] - xl) / dx)
    if dy > 0.0:
        t = min(t, (min(by + bsize, ny) * gf[G_DY] - yl) / dy)
    elif dy < 0.0:
        t = min(t, (by * gf[G_DY] - yl) / dy)
    r = math.sqrt(px * px + py * py + pz * pz)
    rate = (px * dx + py * dy + pz * dz) / r
    h = r - gf[G_RBASE]
    if rate > 0.0:
        t = min(t, (min(bz + bsize, nz) * gf[G_DZ] - h) / rate)
    elif rate < 0.0:
        t = min(t, (bz * gf[G_DZ] - h) / rate)
    return max(t, 0.0)


@parallel_kernel
def march_rays(origin, dirs, sun, gf, rho, occupied, bsize, tau_sun, tau_above, tau_below, k, albedo, ph_mu, ph_val,
               g, solar, mu0, dmu, t_atm, e_down, e_up, mp, n_octaves, linear, thin_aware, radiance, transmittance,
               depth, hit):
    """March view rays ``dirs`` (n, 3) from ``origin`` (3,) through the field (module docstring of
    :mod:`.broken_cloud`): the cloud's radiance reaching the eye through the cloud ``radiance`` (n, n_wl) [W m^-2
    sr^-1 nm^-1], the cloud's transmittance along the ray ``transmittance`` (n, n_wl), the mean depth of the light's
    last scattering ``depth`` (n,) [m] (weights ``T (1 - exp(-sigma dt))`` at the first wavelength) and ``hit`` (n,)
    (the ray met cloud). ``occupied`` (nbx, nby, nbz): 1 where a block of ``bsize`` voxels holds cloud (empty
    blocks are crossed in one step). ``tau_sun``, ``tau_above``, ``tau_below``: optical depths at the reference
    wavelength from each voxel centre to the sun, to the field's top and to its base (vertically). ``k`` (n_wl,)
    extinction relative to the reference wavelength, ``albedo`` single-scattering albedo; ``ph_mu`` (m,),
    ``ph_val`` (n_wl, m) the droplets' phase table; ``g`` its asymmetry; ``solar`` the extraterrestrial irradiance
    [W m^-2 nm^-1]; ``t_atm`` (nz, n_mu, n_wl) the clear air's transmittance to the sun and ``e_down`` (nz, n_mu,
    n_wl) its diffuse irradiance on a horizontal plane [W m^-2 nm^-1] at each voxel layer, for the sun cosines ``mu0
    + i dmu``; ``e_up`` (n_wl,) the ground's upward irradiance [W m^-2 nm^-1]. ``mp``: a, b, c, d (octaves and
    ambient extinction), the step as a fraction of the voxel along the axis the ray crosses fastest [-], the
    level-of-detail factor (step >= lod * distance) and the ray start distance. ``linear``: the densities and
    optical depths interpolated trilinearly between voxel centres (smooth cloud edges; ``occupied`` must then count
    a voxel's neighbours); else constant per voxel (the field's definition, the Monte Carlo's). ``thin_aware``:
    octave ``i`` weighted by ``(1 - exp(-tau_column))^i`` (:mod:`.broken_cloud`).
    """
    n = dirs.shape[0]
    nwl = k.shape[0]
    nx, ny, nz = rho.shape
    nmu = t_atm.shape[1]
    m = ph_mu.shape[0]
    a = mp[M_A]
    b = mp[M_B]
    c = mp[M_C]
    dd = mp[M_D]
    step_fraction = mp[M_STEP]
    lod = mp[M_LOD]
    ox = origin[0]
    oy = origin[1]
    oz = origin[2]
    four_pi = 4.0 * math.pi
    inv_two_pi = 0.5 / math.pi
    kbar = 0.0
    for wl in range(nwl):
        kbar += k[wl] / nwl
    dk = np.empty(nwl)
    dkmax = 0.0
    for wl in range(nwl):
        dk[wl] = k[wl] - kbar
        dkmax = max(dkmax, abs(dk[wl]))
    periodic = gf[G_PERIODIC] != 0.0
    for ray in prange(n):
        dx = dirs[ray, 0]
        dy = dirs[ray, 1]
        dz = dirs[ray, 2]
        # the step: ``step_fraction`` of the voxel along the axis the ray crosses fastest (the altitude's rate taken
        # at the eye: further out the planet's curvature steepens it by at most t / R)
        rate = max(abs(dx) / gf[G_DX], abs(dy) / gf[G_DY], abs(dz) / gf[G_DZ])
        step0 = step_fraction / rate
        tr = np.ones(nwl)
        acc = np.zeros(nwl)
        w = np.empty((n_octaves, nwl))
        direct = np.empty(nwl)
        # phase of each octave towards the eye (a function of the ray only: the sun's rays are parallel)
        # cosine of the scattering angle: the sunlight's direction of travel (-s) . the light's towards the eye (-d)
        mu = dx * sun[0] + dy * sun[1] + dz * sun[2]
        lo = 0
        hi = m - 1
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if ph_mu[mid] <= mu:
                lo = mid
            else:
                hi = mid
        f = (mu - ph_mu[lo]) / (ph_mu[hi] - ph_mu[lo]) if ph_mu[hi] > ph_mu[lo] else 0.0
        f = min(max(f, 0.0), 1.0)
        for wl in range(nwl):
            p0 = ph_val[wl, lo] * (1.0 - f) + ph_val[wl, hi] * f
            w[0, wl] = solar[wl] * p0
            scale = 1.0
            gi = g[wl]
            for o in range(1, n_octaves):
                scale *= b
                gi *= c
                hg = (1.0 - gi * gi) / (four_pi * (1.0 + gi * gi - 2.0 * gi * mu) ** 1.5)
                w[o, wl] = solar[wl] * scale * hg
        # the part of the ray inside the shell between base and top, before the ground
        bb = ox * dx + oy * dy + oz * dz
        cc = ox * ox + oy * oy + oz * oz
        ta, tb = _sphere_roots(bb, cc, gf[G_RTOP])
        ta = max(ta, mp[M_TMIN])
        tg0, tg1 = _sphere_roots(bb, cc, gf[G_RGROUND])
        if tg0 > 0.0 and tg0 < tb:
            tb = tg0
        tc, td = _sphere_roots(bb, cc, gf[G_RBASE])
        # open sides: the part of the ray over the box
        if gf[G_PERIODIC] == 0.0:
            for axis in range(2):
                o_ = ox if axis == 0 else oy
                d_ = dx if axis == 0 else dy
                lo_ = gf[G_X0] if axis == 0 else gf[G_Y0]
                hi_ = lo_ + (gf[G_LX] if axis == 0 else gf[G_LY])
                if d_ == 0.0:
                    if o_ < lo_ or o_ > hi_:
                        tb = -math.inf
                else:
                    t1 = (lo_ - o_) / d_
                    t2 = (hi_ - o_) / d_
                    ta = max(ta, min(t1, t2))
                    tb = min(tb, max(t1, t2))
        wsum = 0.0
        wdepth = 0.0
        met = False
        for seg in range(2):
            # the shell is [ta, tb] without the inside of the base sphere (tc, td)
            if seg == 0:
                s0 = ta
                s1 = min(tb, tc) if tc > ta else tb
                if tc <= ta < td:
                    s0 = td
            else:
                if not (ta < tc < td < tb):
                    break
                s0 = td
                s1 = tb
            if s1 <= s0:
                continue
            t = s0
            done = False
            while t < s1:
                step = max(step0, lod * t)
                px = ox + t * dx
                py = oy + t * dy
                pz = oz + t * dz
                ix, iy, iz, inside = _voxel(px, py, pz, gf, nx, ny, nz)
                if inside and occupied[ix // bsize, iy // bsize, iz // bsize] == 0:
                    t += _block_exit(px, py, pz, dx, dy, dz, ix, iy, iz, gf, bsize, nx, ny, nz) + 1e-3
                    continue
                if not inside:
                    t += step
                    continue
                h = min(step, s1 - t)
                tm = t + 0.5 * h
                px = ox + tm * dx
                py = oy + tm * dy
                pz = oz + tm * dz
                ix, iy, iz, inside = _voxel(px, py, pz, gf, nx, ny, nz)
                t += h
                if not inside:
                    continue
                rr = math.sqrt(px * px + py * py + pz * pz)
                if linear:
                    fx = (px - gf[G_X0]) / gf[G_DX]
                    fy = (py - gf[G_Y0]) / gf[G_DY]
                    fz = (rr - gf[G_RBASE]) / gf[G_DZ]
                    r = _trilinear(rho, fx, fy, fz, periodic)
                    if r <= 0.0:
                        continue
                    ts = _trilinear(tau_sun, fx, fy, fz, periodic)
                    tup = _trilinear(tau_above, fx, fy, fz, periodic)
                    tdn = _trilinear(tau_below, fx, fy, fz, periodic)
                else:
                    r = rho[ix, iy, iz]
                    if r <= 0.0:
                        continue
                    ts = tau_sun[ix, iy, iz]
                    tup = tau_above[ix, iy, iz]
                    tdn = tau_below[ix, iy, iz]
                met = True
                # the sun's cosine at the point and the clear air's light there (linear in mu)
                mus = (px * sun[0] + py * sun[1] + pz * sun[2]) / rr
                fm = (mus - mu0) / dmu
                fm = min(max(fm, 0.0), nmu - 1.0)
                j = min(int(fm), nmu - 2)
                fm -= j
                # the sun's octaves: exp(-a^i tau k_l) = exp(-x kbar) exp(-x dk_l), x = a^i tau; the second factor by
                # its Taylor polynomial where x max|dk| < 0.02 (error below 1.4e-6), else exactly
                for wl in range(nwl):
                    direct[wl] = 0.0
                att = 1.0
                # octave i scatters i more times: in a column of vertical optical depth tau_c the chance of each
                # further scattering is taken as 1 - exp(-tau_c) (thin wisps do not multiply-scatter)
                pc = -math.expm1(-(tup + tdn)) if thin_aware else 1.0
                pw = 1.0
                for o in range(n_octaves):
                    x = att * ts
                    att *= a
                    po = pw
                    pw *= pc
                    if x * kbar > 40.0:
                        continue
                    base = po * math.exp(-x * kbar)
                    if x * dkmax < 0.02:
                        for wl in range(nwl):
                            y = x * dk[wl]
                            direct[wl] += w[o, wl] * base * (1.0 - y + 0.5 * y * y)
                    else:
                        for wl in range(nwl):
                            direct[wl] += po * w[o, wl] * math.exp(-x * k[wl])
                x = r * h
                base = math.exp(-x * kbar)
                poly = x * dkmax < 0.02
                wmax = 0.0
                for wl in range(nwl):
                    kk = k[wl]
                    tatm = t_atm[iz, j, wl] * (1.0 - fm) + t_atm[iz, j + 1, wl] * fm
                    edn = e_down[iz, j, wl] * (1.0 - fm) + e_down[iz, j + 1, wl] * fm
                    if dd != 0.0:
                        amb = (edn * math.exp(-dd * tup * kk) + e_up[wl] * math.exp(-dd * tdn * kk)) * inv_two_pi
                    else:
                        amb = (edn + e_up[wl]) * inv_two_pi
                    src = albedo[wl] * (direct[wl] * tatm + amb)
                    if poly:
                        y = x * dk[wl]
                        step_t = base * (1.0 - y + 0.5 * y * y)
                    else:
                        step_t = math.exp(-x * kk)
                    acc[wl] += tr[wl] * (1.0 - step_t) * src
                    if wl == 0:
                        wgt = tr[0] * (1.0 - step_t)
                        wsum += wgt
                        wdepth += wgt * tm
                    tr[wl] *= step_t
                    if tr[wl] > wmax:
                        wmax = tr[wl]
                if wmax < T_STOP:
                    done = True
                    break
            if done:
                break
        for wl in range(nwl):
            radiance[ray, wl] = acc[wl]
            transmittance[ray, wl] = tr[wl]
        depth[ray] = wdepth / wsum if wsum > 0.0 else 0.0
        hit[ray] = met

