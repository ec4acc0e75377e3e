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

from ..jit import CONTRACT_ARCP, helper, inline, kernel
from ..montecarlo.tracking import box_clip, field_transmittance
from ..precomputed.geometry import bilinear_weights
from ..vecmath import exp_lanes

__all__ = ["march_rays", "shadow_volume", "ground_shadow", "shaft_loss"]

# layout of the float geometry ``gf``
G_X0, G_Y0, G_DX, G_DY, G_DZ, G_LX, G_LY, G_RBASE, G_RTOP, G_RGROUND, G_PERIODIC = range(11)
# layout of the march parameters ``mp``
M_A, M_B, M_C, M_D, M_STEP, M_LOD, M_TMIN, M_TOP, M_SIDE, M_BASE = range(10)
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


@helper
def _wrap(u, n):
    """``u`` [voxels] folded into ``[0, n)`` (periodic sides): a float floor instead of an integer modulo."""
    u -= math.floor(u / n) * n
    return u if u < n else 0.0


@inline
def _field_coords(px, py, pz, x0, y0, inv_dx, inv_dy, inv_dz, rbase, nx, ny, nz, periodic):
    """Continuous voxel coordinates ``(fx, fy, fz)`` of a point ``p`` of the march's segments (voxel ``i`` spans
    ``[i, i + 1)``; x and y folded into the field when it is periodic), its distance from the planet's centre [m]
    and whether it is over the field's box. The segments lie between the base and top spheres by construction, so
    ``fz`` is clamped into ``[0, nz)``: a segment starting on the base sphere (a view from below) computes a radius a
    rounding below it, and a test on ``fz`` then skipped the segment's first step (54 m of cloud at 60 deg)."""
    fx = (px - x0) * inv_dx
    fy = (py - y0) * inv_dy
    if periodic:
        fx = _wrap(fx, nx)
        fy = _wrap(fy, ny)
    r = math.sqrt(px * px + py * py + pz * pz)
    fz = min(max((r - rbase) * inv_dz, 0.0), nz * (1.0 - 1e-12))
    return fx, fy, fz, r, (0.0 <= fx < nx and 0.0 <= fy < ny)


@kernel(fastmath=CONTRACT_ARCP)
def march_rays(origin, dirs, sun, gf, vol, occupied, bsize, k, ph_mu, oct_val, g, solar, mu0, dmu, src_sun,
               src_amb, amb_up, mp, n_octaves, linear, thin_aware, radiance, transmittance, depth, hit, start, stop):
    """March view rays ``dirs[start:stop]`` (of (n, 3)) from ``origin`` (3,) through the field (module docstring of
    :mod:`.broken_cloud`; called through :func:`skyscatter.precomputed.parallel.parallel_for`, no allocation per
    ray): the cloud's radiance reaching the eye through the cloud ``radiance`` (n, n_wl) [W m^-2 sr^-1 nm^-1], the
    cloud's transmittance along the ray ``transmittance`` (n, n_wl), the mean depth of the light's last scattering
    ``depth`` (n,) [m] (weights ``T (1 - exp(-sigma dt))`` at the first wavelength) and ``hit`` (n,) (the ray met
    cloud).

    ``vol`` (nx + 2, ny + 2, nz, 4): per voxel centre the extinction at the reference wavelength [m^-1], the
    optical depth at the reference wavelength to the sun, and the extinction times the (vertical) optical depths to
    the field's top and to its base (divided by the interpolated extinction after the read: the depths weighted by
    the cloud each voxel brings to the point, so that a cloud's side wall is not given its clear neighbours' zero
    depths; docs/clouds.md, "Vertical streaks"), with
    one ghost voxel on each horizontal side (the opposite side's for periodic fields, the edge voxel repeated
    for open ones), so that the interpolation needs no modulo and no clamping in x and y; float32 (relative
    rounding 6e-8, far below the march's own error). ``occupied`` (nx, ny, nz): 1 where the voxel's block of
    ``bsize`` voxels holds cloud (empty blocks are crossed in one step). ``k`` (n_wl,) extinction relative to the
    reference wavelength (the march's: delta-M scaled, :func:`.broken_cloud.delta_m_octaves`); ``ph_mu`` (m,)
    ascending cosines of the scattering angle and ``oct_val`` (n_octaves, n_wl, m) [sr^-1] each octave's phase
    function there (:func:`.broken_cloud.octave_phases`; octave 0 the droplets' tabulated phase times its delta-M
    factor ``1 / (1 - omega f)``, :func:`.broken_cloud.delta_m_octaves`); ``g`` the droplets' asymmetry;
    ``solar`` the extraterrestrial irradiance [W m^-2 nm^-1]; ``src_sun`` (nz, n_mu, n_wl) the single-scattering
    albedo times the clear air's transmittance to the sun, ``src_amb`` (nz, n_mu, n_wl) the albedo times the clear
    air's diffuse irradiance on a horizontal plane / (2 pi) [W m^-2 nm^-1 sr^-1] at each voxel layer, for the sun
    cosines ``mu0 + i dmu``; ``amb_up`` (n_wl,) the albedo times the ground's upward irradiance / (2 pi). ``mp``:
    a, b, c, d (octaves and ambient extinction; ``c`` unused here: ``oct_val`` holds it), the step as a fraction
    of the voxel along the axis the ray crosses fastest [-], the level-of-detail factor (step >= lod * distance),
    the ray start distance and the factors of the
    octaves ``i >= 1`` for the energy entering the clouds through their tops and through their sides
    (:func:`.broken_cloud.entry_factors`), blended per sample by the share of the sun's path that runs through
    the cloud above the point, ``min(tau_sun mu_s / tau_top, 1)``; and the switch (nonzero: on) of the
    diffusion's profile near a thick cloud's base (:data:`.broken_cloud.BASE_PROFILE`). ``linear``: the
    densities and optical depths interpolated trilinearly between voxel centres (smooth cloud edges; ``occupied``
    must then count a voxel's neighbours); else constant per voxel (the field's definition, the Monte Carlo's).
    ``thin_aware``: octave ``i`` weighted by ``(1 - exp(-tau_column))^i`` (:mod:`.broken_cloud`).
    """
    nwl = k.shape[0]
    nx = vol.shape[0] - 2
    ny = vol.shape[1] - 2
    nz = vol.shape[2]
    nmu = src_sun.shape[1]
    m = ph_mu.shape[0]
    a = mp[M_A]
    b = mp[M_B]
    dd = mp[M_D]
    step_fraction = mp[M_STEP]
    lod = mp[M_LOD]
    ox = origin[0]
    oy = origin[1]
    oz = origin[2]
    x0 = gf[G_X0]
    y0 = gf[G_Y0]
    inv_dx = 1.0 / gf[G_DX]
    inv_dy = 1.0 / gf[G_DY]
    inv_dz = 1.0 / gf[G_DZ]
    rbase = gf[G_RBASE]
    periodic = gf[G_PERIODIC] != 0.0
    kbar = 0.0
    gbar = 0.0
    for wl in range(nwl):
        kbar += k[wl] / nwl
        gbar += g[wl] / nwl
    # the wavelength of the smallest extinction keeps the largest transmittance (every step's factor decreases with
    # k): the march stops when it is below T_STOP
    wl_min = 0
    dk = np.empty(nwl)
    dkmax = 0.0
    for wl in range(nwl):
        dk[wl] = k[wl] - kbar
        dkmax = max(dkmax, abs(dk[wl]))
        if k[wl] < k[wl_min]:
            wl_min = wl
    tr = np.empty(nwl)
    acc = np.empty(nwl)
    w = np.empty((n_octaves, nwl))
    # w times (-dk_l)^j / j!, j = 1..4: the Taylor terms of exp(-x dk_l) per octave (below)
    wt = np.empty((4, n_octaves, nwl))
    tj = np.empty((4, nwl))
    for wl in range(nwl):
        cj = 1.0
        for jj in range(4):
            cj *= -dk[wl] / (jj + 1)
            tj[jj, wl] = cj
    direct = np.empty(nwl)
    # the octaves' extinction factors a^i (the same products as the octave loop's running one) and a buffer for
    # their exponentials and the step's, computed together per sample (:func:`skyscatter.vecmath.exp_lanes`)
    a_pow = np.empty(n_octaves)
    att = 1.0
    for o in range(n_octaves):
        a_pow[o] = att
        att *= a
    ez = np.empty(n_octaves + 1)
    el = np.empty(nwl)  # the same for an octave's exponentials per wavelength where the polynomial is not used
    # the diffusion profile near the cloud base (below): on or off, and 1 - g
    base_on = mp[M_BASE] != 0.0
    gm1 = 1.0 - gbar
    for ray in range(start, stop):
        dx = dirs[ray, 0]
        dy = dirs[ray, 1]
        dz = dirs[ray, 2]
        # the cosine of the light's downward travel towards the eye with the eye's vertical (the ray's elevation;
        # over a field of tens of kilometres the vertical turns by < 1e-2 rad), 0 for light travelling upwards
        mu_down = max((dx * ox + dy * oy + dz * oz) / math.sqrt(ox * ox + oy * oy + oz * oz), 0.0)
        # the step: ``step_fraction`` of the voxel along the axis the ray crosses fastest (the altitude's rate taken
        # at the eye: further out the planet's curvature steepens it by at most t / R)
        rate = max(abs(dx) * inv_dx, abs(dy) * inv_dy, abs(dz) * inv_dz)
        step0 = step_fraction / rate
        for wl in range(nwl):
            tr[wl] = 1.0
            acc[wl] = 0.0
        # the part of the ray inside the shell between base and top, before the ground
        bb = ox * dx + oy * dy + oz * dz
        cc = ox * ox + oy * oy + oz * oz
        ta, tb = _sphere_roots(bb, cc, gf[G_RTOP])
        ta = max(ta, mp[M_TMIN])
        tg0, tg1 = _sphere_roots(bb, cc, gf[G_RGROUND])
        if bb < 0.0 and tg1 > 0.0:
            # a ray heading into the ground stops there; from an eye on the ground (tg0 = 0 up to rounding) at once,
            # not through the planet to the clouds on its far side
            tb = min(tb, max(tg0, 0.0))
        tc, td = _sphere_roots(bb, cc, rbase)
        # open sides: the part of the ray over the box
        if not periodic:
            ta, tb = box_clip(ox, oy, dx, dy, x0, y0, gf[G_LX], gf[G_LY], ta, tb)
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
                # the voxel at t: in an empty block, jump to the block's exit
                fx, fy, fz, rr, inside = _field_coords(px, py, pz, x0, y0, inv_dx, inv_dy, inv_dz, rbase, nx, ny, nz,
                                                       periodic)
                if inside:
                    ix = int(fx)
                    iy = int(fy)
                    iz = int(fz)
                    if occupied[ix, iy, iz] == 0:
                        t += _block_exit(px, py, pz, dx, dy, dz, ix, iy, iz, gf, bsize, nx, ny, nz) + 1e-3
                        continue
                else:
                    t += step
                    continue
                # midpoint sample of the step
                h = min(step, s1 - t)
                tm = t + 0.5 * h
                t += h
                px = ox + tm * dx
                py = oy + tm * dy
                pz = oz + tm * dz
                fx, fy, fz, rr, inside = _field_coords(px, py, pz, x0, y0, inv_dx, inv_dy, inv_dz, rbase, nx, ny, nz,
                                                       periodic)
                if not inside:
                    continue
                iz = int(fz)
                if linear:
                    # trilinear between voxel centres: ghost voxels in x and y, clamped in z (a horizontally uniform
                    # field stays uniform up to its faces)
                    u = fx + 0.5
                    v = fy + 0.5
                    i0 = int(u)
                    j0 = int(v)
                    fu = u - i0
                    fv = v - j0
                    if nz > 1:
                        ww = min(max(fz - 0.5, 0.0), nz - 1.0)
                        k0 = min(int(ww), nz - 2)
                        fw = ww - k0
                        k1 = k0 + 1
                    else:
                        k0 = 0
                        k1 = 0
                        fw = 0.0
                    q00, q01, q10, q11 = bilinear_weights(fu, fv)
                    w000 = q00 * (1.0 - fw)
                    w100 = q10 * (1.0 - fw)
                    w010 = q01 * (1.0 - fw)
                    w110 = q11 * (1.0 - fw)
                    w001 = q00 * fw
                    w101 = q10 * fw
                    w011 = q01 * fw
                    w111 = q11 * fw
                    r = (w000 * vol[i0, j0, k0, 0] + w100 * vol[i0 + 1, j0, k0, 0] + w010 * vol[i0, j0 + 1, k0, 0]
                         + w110 * vol[i0 + 1, j0 + 1, k0, 0] + w001 * vol[i0, j0, k1, 0]
                         + w101 * vol[i0 + 1, j0, k1, 0] + w011 * vol[i0, j0 + 1, k1, 0]
                         + w111 * vol[i0 + 1, j0 + 1, k1, 0])
                    if r <= 0.0:
                        continue
                    ts = 0.0
                    tup = 0.0
                    tdn = 0.0
                    tb = 0.0
                    for q in range(1, 4):
                        val = (w000 * vol[i0, j0, k0, q] + w100 * vol[i0 + 1, j0, k0, q]
                               + w010 * vol[i0, j0 + 1, k0, q] + w110 * vol[i0 + 1, j0 + 1, k0, q]
                               + w001 * vol[i0, j0, k1, q] + w101 * vol[i0 + 1, j0, k1, q]
                               + w011 * vol[i0, j0 + 1, k1, q] + w111 * vol[i0 + 1, j0 + 1, k1, q])
                        if q == 1:
                            ts = val
                        elif q == 2:
                            tup = val / r
                        else:
                            tdn = val / r
                            tb = tdn
                else:
                    ix = int(fx) + 1
                    iy = int(fy) + 1
                    r = float(vol[ix, iy, iz, 0])
                    if r <= 0.0:
                        continue
                    ts = float(vol[ix, iy, iz, 1])
                    tup = float(vol[ix, iy, iz, 2]) / r
                    tdn = float(vol[ix, iy, iz, 3]) / r
                    # the optical depth above the base at the sample itself (the voxel's is at its centre)
                    tb = tdn + (fz - iz - 0.5) * r * gf[G_DZ]
                if not met:
                    # phase of each octave towards the eye (a function of the ray only: the sun's rays are parallel),
                    # computed at the ray's first cloud sample (rays that meet none never need it)
                    # cosine of the scattering angle: the sunlight's direction of travel (-s) . the light's towards
                    # the eye (-d)
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
                    # every octave's tabulated phase at the same node pair, octave i scattering b^i as much
                    scale = 1.0
                    for o in range(n_octaves):
                        for wl in range(nwl):
                            w[o, wl] = solar[wl] * scale * (oct_val[o, wl, lo] * (1.0 - f) + oct_val[o, wl, hi] * f)
                        scale *= b
                    for o in range(n_octaves):
                        for jj in range(4):
                            for wl in range(nwl):
                                wt[jj, o, wl] = w[o, wl] * tj[jj, wl]
                met = True
                # the sun's cosine at the point and the clear air's light there (linear in mu)
                mus = (px * sun[0] + py * sun[1] + pz * sun[2]) / rr
                fm = (mus - mu0) / dmu
                fm = min(max(fm, 0.0), nmu - 1.0)
                j = min(int(fm), nmu - 2)
                fm -= j
                # the sun's octaves: exp(-a^i tau k_l) = exp(-x kbar) exp(-x dk_l), x = a^i tau; the second factor by
                # its Taylor polynomial of degree 2, 3 or 4 where y = x max|dk| < 0.02, 0.1 or 0.25 (remainder
                # y^(n+1) e^y / (n+1)! below 1.4e-6, 4.6e-6 and 1.1e-5 of the octave), else exactly (a thick cloud's
                # tau_sun of 10-25 needs the higher degrees: 16 exponentials per octave were the octaves' cost).
                # Octave i scatters i
                # more times: in a column of vertical optical depth tau_c the chance of each further scattering is
                # taken as 1 - exp(-tau_c) (thin wisps do not multiply-scatter)
                pc = -math.expm1(-(tup + tdn)) if thin_aware else 1.0
                # light entering through the top: the sun's path from the point leaves through the cloud above it,
                # its optical depth tau_top / mu_s (a horizontally uniform cloud); less means it leaves by a side
                ftop = min(ts * mus / tup, 1.0) if tup > 1e-6 and mus > 0.0 else 1.0
                entry = ftop * mp[M_TOP] + (1.0 - ftop) * mp[M_SIDE]
                if base_on:
                    # the diffused light near a thick cloud's base (:data:`.broken_cloud.BASE_PROFILE`): the
                    # conservative Eddington layer's source there, I1 (2/3 + (1 - g) tau_b + g mu) ([Joseph1976]'s
                    # equations without the delta scaling; tau_b the optical depth above the base, mu the cosine of
                    # the light's downward travel), relative to the octaves' flat source taken as I1 4/3 (so that the
                    # flux leaving the base is kept: 2 int mu (2/3 + mu) dmu = 4/3); the mean radiance's part capped
                    # at 1 where it reaches 4/3 ((1 - g) tau_b = 2/3), the anisotropy g mu / (2/3 + (1 - g) tau_b)
                    # fading above; phased in over (1 - g) tau_c from 0.7 to 1.4 (column optical depths of about
                    # 5 to 10), below which the octaves' own attenuation to the sun shapes the light
                    i0 = 2.0 / 3.0 + gm1 * max(tb, 0.0)
                    hb = min(0.75 * i0, 1.0) * (1.0 + gbar * mu_down / i0)
                    wcol = min(max((gm1 * (tup + tdn) - 0.7) / 0.7, 0.0), 1.0)
                    entry *= 1.0 + wcol * (hb - 1.0)
                # every octave's exp(-x kbar) and the step's exp(-sigma h kbar) at once
                for o in range(n_octaves):
                    ez[o] = -(a_pow[o] * ts) * kbar
                ez[n_octaves] = -(r * h) * kbar
                exp_lanes(ez, n_octaves + 1)
                pw = 1.0
                for wl in range(nwl):
                    direct[wl] = 0.0
                for o in range(n_octaves):
                    x = a_pow[o] * ts
                    po = pw
                    pw *= pc
                    if o == 0:
                        pw *= entry  # octaves >= 1 only
                    if x * kbar > 40.0 or po == 0.0:
                        continue
                    y = x * dkmax
                    if y < 0.25:
                        cb = po * ez[o]
                        x2 = x * x
                        if y < 0.02:
                            for wl in range(nwl):
                                direct[wl] += w[o, wl] * cb + wt[0, o, wl] * (cb * x) + wt[1, o, wl] * (cb * x2)
                        elif y < 0.1:
                            for wl in range(nwl):
                                direct[wl] += (w[o, wl] * cb + wt[0, o, wl] * (cb * x) + wt[1, o, wl] * (cb * x2)
                                               + wt[2, o, wl] * (cb * x2 * x))
                        else:
                            for wl in range(nwl):
                                direct[wl] += (w[o, wl] * cb + wt[0, o, wl] * (cb * x) + wt[1, o, wl] * (cb * x2)
                                               + wt[2, o, wl] * (cb * x2 * x) + wt[3, o, wl] * (cb * x2 * x2))
                    else:
                        for wl in range(nwl):
                            el[wl] = -x * k[wl]
                        exp_lanes(el, nwl)
                        for wl in range(nwl):
                            direct[wl] += po * w[o, wl] * el[wl]
                # the step's transmittance exp(-x k_l), x = sigma h: the same expansion about kbar
                x = r * h
                base = ez[n_octaves]
                poly = x * dkmax < 0.02
                bx = base * x
                bxx = 0.5 * bx * x
                amb_down = 1.0 if dd == 0.0 else math.exp(-dd * tup * kbar)
                # the ground's light: a column of optical depth tau_c reflects the fraction R = x / (1 + x),
                # x = 3/4 (1 - g) tau_c, of a diffuse irradiance from below (the conservative Eddington layer's
                # reflectance averaged over the incident cosines, thick limit); a source E/(2 pi) seen through the
                # column sends E/2 back down, so it is scaled by 2R
                xr = 0.75 * (1.0 - gbar) * (tup + tdn)
                fup = 2.0 * xr / (1.0 + xr)
                t0 = tr[0]
                for wl in range(nwl):
                    ssun = src_sun[iz, j, wl] * (1.0 - fm) + src_sun[iz, j + 1, wl] * fm
                    samb = src_amb[iz, j, wl] * (1.0 - fm) + src_amb[iz, j + 1, wl] * fm
                    if dd == 0.0:
                        src = direct[wl] * ssun + samb + amb_up[wl] * fup
                    else:
                        src = (direct[wl] * ssun + samb * amb_down * math.exp(-dd * tup * dk[wl])
                               + amb_up[wl] * fup * math.exp(-dd * tdn * k[wl]))
                    if poly:
                        e = dk[wl]
                        step_t = base - e * bx + e * e * bxx
                    else:
                        step_t = math.exp(-x * k[wl])
                    acc[wl] += tr[wl] * (1.0 - step_t) * src
                    tr[wl] *= step_t
                wgt = t0 - tr[0]
                wsum += wgt
                wdepth += wgt * tm
                if tr[wl_min] < T_STOP:
                    done = True
                    break
            if done:
                break
        for wl in range(nwl):
            radiance[ray, wl] = acc[wl]
            transmittance[ray, wl] = tr[wl]
        depth[ray] = wdepth / wsum if wsum > 0.0 else 0.0
        hit[ray] = met


@inline
def _shaft_node(h, mu_s, h_step, beta_r, beta_m, beta_e, src, mu0, dmu, p_r, p_m, rho_r, rho_m, t_view, out, be):
    """The shafts' integrands at a node of :func:`shaft_loss` at altitude ``h`` [m] and sun cosine ``mu_s``, every
    wavelength ``l``, per unit of the Rayleigh and the particles' scalar profiles ``rho_r``, ``rho_m`` (n_h,) (zero:
    the part is zero), for the phase functions ``p_r`` and ``p_m`` (n_wl,) [sr^-1], into ``out`` (4, n_wl):
    ``T beta_R P_R E_0 T_air / rho_R``, ``T beta_M P_M E_0 T_air / rho_M`` (the loss), ``T beta_R / rho_R``,
    ``T beta_M / rho_M`` (the gain); ``be`` the air's extinction [m^-1]; ``t_view`` the air's transmittance from
    the eye. The coefficients linear between the altitude nodes ``h_step``
    [m] apart, ``E_0 T_air`` bilinear in altitude and the sun cosines ``mu0 + i dmu``."""
    n_h = beta_e.shape[0]
    n_mu = src.shape[1]
    u = min(max(h / h_step, 0.0), n_h - 1.0)
    i_h = min(int(u), n_h - 2)
    a_h = u - i_h
    v = min(max((mu_s - mu0) / dmu, 0.0), n_mu - 1.0)
    i_m = min(int(v), n_mu - 2)
    a_m = v - i_m
    pr = (1.0 - a_h) * rho_r[i_h] + a_h * rho_r[i_h + 1]
    pm = (1.0 - a_h) * rho_m[i_h] + a_h * rho_m[i_h + 1]
    inv_r = 1.0 / pr if pr > 0.0 else 0.0
    inv_m = 1.0 / pm if pm > 0.0 else 0.0
    for w in range(t_view.shape[0]):
        be[w] = (1.0 - a_h) * beta_e[i_h, w] + a_h * beta_e[i_h + 1, w]
        br = ((1.0 - a_h) * beta_r[i_h, w] + a_h * beta_r[i_h + 1, w]) * t_view[w] * inv_r
        bm = ((1.0 - a_h) * beta_m[i_h, w] + a_h * beta_m[i_h + 1, w]) * t_view[w] * inv_m
        e0 = ((1.0 - a_h) * ((1.0 - a_m) * src[i_h, i_m, w] + a_m * src[i_h, i_m + 1, w])
              + a_h * ((1.0 - a_m) * src[i_h + 1, i_m, w] + a_m * src[i_h + 1, i_m + 1, w]))
        out[0, w] = br * p_r * e0
        out[1, w] = bm * p_m[w] * e0
        out[2, w] = br
        out[3, w] = bm


@kernel(fastmath=CONTRACT_ARCP)
def shaft_loss(origin, dirs, seg, t0, sun, gf, tau_ground, tau_sun, h_step, beta_r, beta_m, beta_e, rho_r, rho_m,
               src, mu0, dmu, p_r, ph_mu, ph_val, k, step, growth, group, cloud_light, out, gain, start, stop):
    """The single-scattered sunlight of the air that the field's shadow removes along each view ray (light shafts
    below the clouds), rays ``start..stop``, into ``out`` (n, n_wl) [W m^-2 sr^-1 nm^-1].

    The single-scattering integral ([Bruneton2008] Eq. 11 with the sun's light L0 of Eq. 9, the one its single Rayleigh
    and Mie tables hold): ``dL = T(eye, p) (beta_R(h) P_R(nu) + beta_M(h) P_M(nu)) E_0 T_air(h, mu_s) dt``, here times
    ``1 - exp(-tau k)``, the fraction of the sunlight the field takes away at ``p`` (``tau`` its optical depth to the
    sun at 550 nm, ``k`` the droplets' relative extinction). Midpoint steps along ``[t0, t0 + seg]`` of ``step`` [m]
    growing as ``growth`` x the distance. ``T(eye, p)`` starts at ``out[q]`` (the air's transmittance from the eye to
    the segment's start, given in ``out``). ``p_r`` (n,) the Rayleigh phase function of each ray [sr^-1]; the
    aerosol's linear in the cosine of the scattering angle between the table's cosines ``ph_mu`` (m,) ascending,
    values ``ph_val`` (n_wl, m) (:meth:`~skyscatter.atmosphere.phase_table.PhaseTable.evaluate`'s rule).
    ``tau``: below the base the ground map ``tau_ground`` (nx, ny) at the foot of the point's sun ray (bilinear between
    the columns' centres; periodic fields wrap, open ones give 0 outside the box), in the layer the shadow volume
    ``tau_sun`` (nx, ny, nz) of the voxel.

    In the same steps, the clouds' light the air scatters towards the eye, into ``gain`` (n, n_wl)
    [W m^-2 sr^-1 nm^-1]: ``int T(eye, p) (beta_R(h) + beta_M(h)) dL dt`` at the points over the field (periodic
    fields: everywhere), ``dL = cloud_light`` (n_wl,) [W m^-2 sr^-1 nm^-1] the change the clouds make to the mean
    radiance over the sphere (an isotropic field: the phase functions integrate to 1); zeros: no gain.

    Cost: the shadow changes from step to step (voxels of ~100 m), the air's spectral integrand slowly. Each step
    computes scalars only: its ``tau``, the shadow's spectral moments and the Rayleigh and particle profiles
    ``rho_r``, ``rho_m`` (n_h,) at its altitude (the coefficients' altitude dependence when they are separable,
    ``beta(h, l) = rho(h) beta(l)``: the caller checks). The integrands per unit profile at every wavelength
    (:func:`_shaft_node`) are computed at nodes, the midpoints of some steps, and taken linear in the distance
    between them. A step is a node when it is the first or the last, or when the next step would take the group
    since the last node beyond ``group`` = (steps, the air's optical length at the most extinguished wavelength
    along the ray or towards the sun, ``|dh| beta_e / mu_s`` [-]); the air's transmittance between nodes by the
    trapezoid of their extinctions. ``group[0] = 1``: every step a node (the integrand at every step's midpoint).
    The shadow's factor ``1 - exp(-tau k_l) = 1 - exp(-tau kbar) exp(-tau dk_l)`` by the cubic Taylor polynomial of
    the second factor, ``sum_j c_j dk_l^j``, the ``c_j`` scalars summed per group: its error is below
    ``max_tau exp(-tau kbar) (tau dk)^4 / 24 = 0.195 (dk / kbar)^4`` (< 4e-5 for the droplets of 1-50 um, ``|dk| /
    kbar <= 0.12``)."""
    n_l = k.shape[0]
    n_h = beta_e.shape[0]
    nx, ny, nz = tau_sun.shape
    x0, y0 = gf[G_X0], gf[G_Y0]
    inv_dx, inv_dy, inv_dz = 1.0 / gf[G_DX], 1.0 / gf[G_DY], 1.0 / gf[G_DZ]
    rbase, rground = gf[G_RBASE], gf[G_RGROUND]
    periodic = gf[G_PERIODIC] != 0.0
    g_steps = int(group[0])
    g_tau = group[1]
    sx, sy, sz = sun[0], sun[1], sun[2]
    t_view = np.empty(n_l)
    acc = np.empty(n_l)
    acc_gain = np.empty(n_l)
    a0 = np.empty((4, n_l))
    a1 = np.empty((4, n_l))
    be0 = np.empty(n_l)
    be1 = np.empty(n_l)
    dk = np.empty(n_l)
    p_aer = np.empty(n_l)
    # the air's transmittance over a step or between nodes at every wavelength, by
    # :func:`skyscatter.vecmath.exp_lanes` (one vectorised loop instead of a libm call per wavelength)
    ez = np.empty(n_l)
    m_ph = ph_mu.shape[0]
    # per group: the shadow's moments sum c_j rho dt and sum c_j rho s dt (j = 0..3; Rayleigh then particles), and
    # over the field sum rho dt, sum rho s dt (Rayleigh, particles); s the distance from the group's first node
    mom = np.zeros(20)
    lit = False
    kbar = 0.0
    for w in range(n_l):
        lit = lit or cloud_light[w] != 0.0
        kbar += k[w] / n_l
    for w in range(n_l):
        dk[w] = k[w] - kbar
    for q in range(start, stop):
        length = seg[q]
        for w in range(n_l):
            t_view[w] = out[q, w]
            acc[w] = 0.0
            acc_gain[w] = 0.0
        if not length > 0.0:
            for w in range(n_l):
                out[q, w] = 0.0
                gain[q, w] = 0.0
            continue
        dx, dy, dz = dirs[q, 0], dirs[q, 1], dirs[q, 2]
        # the aerosol's phase function at the ray's scattering angle: the sunlight's direction of travel (-s) . the
        # light's towards the eye (-d)
        nu = min(max(dx * sx + dy * sy + dz * sz, -1.0), 1.0)
        lo = 0
        hi = m_ph - 1
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if ph_mu[mid] <= nu:
                lo = mid
            else:
                hi = mid
        f_ph = (nu - ph_mu[lo]) / (ph_mu[lo + 1] - ph_mu[lo])
        for w in range(n_l):
            p_aer[w] = (1.0 - f_ph) * ph_val[w, lo] + f_ph * ph_val[w, lo + 1]
        t = t0[q]
        t_end = t0[q] + length
        first = True
        count = 0
        t_node = 0.0
        h_prev = 0.0
        h_node = 0.0
        be_max = 0.0
        mu_node = 1.0
        for j in range(20):
            mom[j] = 0.0
        while t < t_end:
            dt = min(max(step, growth * t), t_end - t)
            tm = t + 0.5 * dt
            px = origin[0] + tm * dx
            py = origin[1] + tm * dy
            pz = origin[2] + tm * dz
            r = math.sqrt(px * px + py * py + pz * pz)
            h = r - rground
            mu_s = (px * sx + py * sy + pz * sz) / r
            # the field's optical depth to the sun from p
            if r < rbase:
                # the foot of the sun ray on the ground (the tangent plane at the point: the sun ray's curvature
                # over a few km is below a metre)
                lift = h / max(mu_s, 1e-3)
                fx = (px - lift * sx - x0) * inv_dx - 0.5
                fy = (py - lift * sy - y0) * inv_dy - 0.5
                i0 = int(math.floor(fx))
                j0 = int(math.floor(fy))
                ax = fx - i0
                ay = fy - j0
                tau = 0.0
                for a in range(2):
                    for b in range(2):
                        ii = i0 + a
                        jj = j0 + b
                        if periodic:
                            ii %= nx
                            jj %= ny
                        elif ii < 0 or ii >= nx or jj < 0 or jj >= ny:
                            continue
                        wgt = (ax if a else 1.0 - ax) * (ay if b else 1.0 - ay)
                        tau += wgt * tau_ground[ii, jj]
            else:
                fx = (px - x0) * inv_dx
                fy = (py - y0) * inv_dy
                if periodic:
                    fx = _wrap(fx, nx)
                    fy = _wrap(fy, ny)
                iz = min(max(int((r - rbase) * inv_dz), 0), nz - 1)
                if 0.0 <= fx < nx and 0.0 <= fy < ny:
                    tau = tau_sun[min(int(fx), nx - 1), min(int(fy), ny - 1), iz]
                else:
                    tau = 0.0
            # the clouds' light on the air: where the point is over the field
            over = False
            if lit:
                if periodic:
                    over = True
                else:
                    gx = (px - x0) * inv_dx
                    gy = (py - y0) * inv_dy
                    over = 0.0 <= gx < nx and 0.0 <= gy < ny
            t += dt
            # the shadow's moments: 1 - exp(-tau k_l) = sum_j c_j dk_l^j (times dt)
            if tau > 0.0:
                e = math.exp(-tau * kbar)
                c0 = (1.0 - e) * dt
                c1 = e * tau * dt
                c2 = -0.5 * c1 * tau
                c3 = -c2 * tau / 3.0
            else:
                c0 = c1 = c2 = c3 = 0.0
            if first:
                # the first node: the air's transmittance to the step's midpoint
                _shaft_node(h, mu_s, h_step, beta_r, beta_m, beta_e, src, mu0, dmu, p_r[q], p_aer, rho_r, rho_m,
                            t_view, a0, be0)
                u = min(max(h / h_step, 0.0), n_h - 1.0)
                i_h = min(int(u), n_h - 2)
                a_h = u - i_h
                pr = (1.0 - a_h) * rho_r[i_h] + a_h * rho_r[i_h + 1]
                pm = (1.0 - a_h) * rho_m[i_h] + a_h * rho_m[i_h + 1]
                be_max = 0.0
                for w in range(n_l):
                    ez[w] = -0.5 * be0[w] * dt
                exp_lanes(ez, n_l)
                for w in range(n_l):
                    f = ez[w]
                    for j in range(4):
                        a0[j, w] *= f
                    t_view[w] *= f
                    be_max = max(be_max, be0[w])
                    dkw = dk[w]
                    acc[w] += (a0[0, w] * pr + a0[1, w] * pm) * (c0 + dkw * (c1 + dkw * (c2 + dkw * c3)))
                    if over:
                        acc_gain[w] += (a0[2, w] * pr + a0[3, w] * pm) * dt * cloud_light[w]
                first = False
                t_node = tm
                h_node = h
                h_prev = h
                mu_node = max(mu_s, 0.02)
                continue
            s = tm - t_node
            # the profiles at the step's altitude
            u = min(max(h / h_step, 0.0), n_h - 1.0)
            i_h = min(int(u), n_h - 2)
            a_h = u - i_h
            pr = (1.0 - a_h) * rho_r[i_h] + a_h * rho_r[i_h + 1]
            pm = (1.0 - a_h) * rho_m[i_h] + a_h * rho_m[i_h + 1]
            if c0 != 0.0:
                cr = pr * c0
                cm = pm * c0
                mom[0] += cr
                mom[4] += cr * s
                mom[8] += cm
                mom[12] += cm * s
                cr = pr * c1
                cm = pm * c1
                mom[1] += cr
                mom[5] += cr * s
                mom[9] += cm
                mom[13] += cm * s
                cr = pr * c2
                cm = pm * c2
                mom[2] += cr
                mom[6] += cr * s
                mom[10] += cm
                mom[14] += cm * s
                cr = pr * c3
                cm = pm * c3
                mom[3] += cr
                mom[7] += cr * s
                mom[11] += cm
                mom[15] += cm * s
            if over:
                mom[16] += pr * dt
                mom[17] += pr * dt * s
                mom[18] += pm * dt
                mom[19] += pm * dt * s
            count += 1
            # a node when the next step would take the group beyond its limits (or at the end)
            nxt = max(step, growth * t)
            node = (t >= t_end or count >= g_steps or (s + nxt) * be_max > g_tau
                    or abs(2.0 * h - h_prev - h_node) * be_max > g_tau * mu_node)
            h_prev = h
            if not node:
                continue
            # the integrands at the node; the transmittance to it by the trapezoid of the extinctions
            _shaft_node(h, mu_s, h_step, beta_r, beta_m, beta_e, src, mu0, dmu, p_r[q], p_aer, rho_r, rho_m, t_view,
                        a1, be1)
            be_max = 0.0
            inv_s = 1.0 / s
            for w in range(n_l):
                ez[w] = -0.5 * (be0[w] + be1[w]) * s
            exp_lanes(ez, n_l)
            for w in range(n_l):
                f = ez[w]
                t_view[w] *= f
                for j in range(4):
                    a1[j, w] *= f
                be_max = max(be_max, be1[w])
                dkw = dk[w]
                m0r = mom[0] + dkw * (mom[1] + dkw * (mom[2] + dkw * mom[3]))
                m1r = mom[4] + dkw * (mom[5] + dkw * (mom[6] + dkw * mom[7]))
                m0m = mom[8] + dkw * (mom[9] + dkw * (mom[10] + dkw * mom[11]))
                m1m = mom[12] + dkw * (mom[13] + dkw * (mom[14] + dkw * mom[15]))
                acc[w] += (a0[0, w] * m0r + (a1[0, w] - a0[0, w]) * m1r * inv_s
                           + a0[1, w] * m0m + (a1[1, w] - a0[1, w]) * m1m * inv_s)
                if lit:
                    acc_gain[w] += (a0[2, w] * mom[16] + (a1[2, w] - a0[2, w]) * mom[17] * inv_s
                                    + a0[3, w] * mom[18] + (a1[3, w] - a0[3, w]) * mom[19] * inv_s) * cloud_light[w]
                for j in range(4):
                    a0[j, w] = a1[j, w]
                be0[w] = be1[w]
            for j in range(20):
                mom[j] = 0.0
            count = 0
            t_node = tm
            h_node = h
            mu_node = max(mu_s, 0.02)
        for w in range(n_l):
            out[q, w] = acc[w]
            gain[q, w] = acc_gain[w]
