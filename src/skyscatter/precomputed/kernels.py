"""Numba kernels of the precomputation (Bruneton & Neyret 2008, Algorithm 4.1).

Each kernel fills one table; the steps of the algorithm that call them (orders, wavelengths, units) are in
:mod:`.compute`.
Tables are float32 arrays with a trailing wavelength axis; sums are accumulated in float64.

* :func:`optical_length_kernel` - integral of each density profile from (r, mu) to the top (Eq. 5 without
  the coefficients, so one geometric pass serves every wavelength); trapezoidal rule.
* :func:`direct_irradiance_kernel` - ``E[L0]`` per unit solar irradiance (Eq. 15 for the sun).
* :func:`single_scattering_kernel` - ``S[L0]`` (Eq. 11 with ``L0``) per unit solar irradiance and unit
  scattering coefficient, Rayleigh and Mie kept apart without their phase functions (Sec. 4, "Angular
  precision").
* :func:`scattering_density_kernel` - ``J[L]`` (Eq. 7) of one order from the radiance of the previous order
  and the light reflected by the ground (Eqs. 6, 10).
* :func:`indirect_irradiance_kernel` - ``E[L]`` (Eq. 15) of one order on a horizontal surface.
* :func:`multiple_scattering_kernel` - ``S[L]`` (Eq. 11): integral of ``T J`` along each view ray.

Ray integrals use product integration (:func:`.sampling.exp_segment_weights`): exact when the scattering
coefficient is exponential between two samples and the rest of the integrand linear, which keeps 50 samples
accurate for the 1.2 km aerosol layer on vertical rays where the plain trapezoidal rule is 8 % off.

Reference: [Bruneton2008].
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import CONTRACT_ARCP, CONTRACT_REASSOC, helper, inline, kernel
from .geometry import (
    MU_S_LIMIT_TOLERANCE,
    acos_table,
    bilinear_weights,
    clamp,
    distance_to_bottom,
    distance_to_boundary,
    irradiance_params,
    lerp_index,
    log_lerp_weight,
    mu_s_limit_a,
    point_along_ray,
    ray_hits_ground,
    scattering_mu_s_coord,
    scattering_mu_s_coord_a,
    scattering_mu_s_param,
    scattering_nu_azimuth,
    scattering_nu_coord,
    scattering_nu_param,
    scattering_r_mu_params,
    transmittance_coord,
    transmittance_params,
)
from .sampling import (
    TABLE_PHASE,
    aerosol_phase,
    density_at,
    exp_segment_weights,
    irradiance_lookup,
    lookup4_cell_weighted,
    multiple_lobe,
    phase_table_values,
    r_mu_cell,
    ray_transmittance,
    rayleigh_phase,
    scattering_lookup,
    scattering_lookup_shadow,
    sun_visible_fraction,
    transmittance_segment,
    transmittance_to_top,
)


@kernel
def mu_s_texels(bottom, top, mu_s_min, n_mu_s):
    """``mu_s`` of every texel of the 4D tables (each found by bisection, so computed once per kernel call)."""
    out = np.empty(n_mu_s)
    for i in range(n_mu_s):
        out[i] = scattering_mu_s_param(i, bottom, top, mu_s_min, n_mu_s)
    return out


PI = math.pi
#: 1 as float32: float32 arithmetic stays float32 (a float64 constant makes numba promote it)
ONE32 = np.float32(1.0)


@helper
def ray_sample_distance(i, n_samples, d_end, mu, hits_ground):
    """Distance [m] of sample ``i`` of ``n_samples`` steps along a ray of length ``d_end``: quadratic spacing,
    dense at the end for rays that meet the ground (their lowest points, where the aerosols are) and at the start
    for the others: going up, or down past a perigee, where the light scattered near the ray's origin is the least
    attenuated. With uniform steps a 70 deg slant path through an aerosol optical depth of 0.5 had one of 50 steps
    per scale height and its radiance came out 5-30 % high against DISORT (docs/bruneton.md). Downward rays that
    miss the ground were uniformly sampled until table format 8: turbidity 3, the sun 2 deg up, a ray grazing the
    horizon from 250 m had its single scattering 4.7 % above the independent integral, now 0.9 %; from 42 km the
    aerosol part is 13 % high (the Earth's shadow crosses the ray between two samples; half the samples dense at
    both the start and the perigee gave 22 %; docs/accuracy.md, "Low sun")."""
    u = i / n_samples
    if hits_ground:
        return d_end * (1.0 - (1.0 - u) * (1.0 - u))
    return d_end * u * u


@kernel
def optical_length_kernel(bottom, top, profiles, counts, n_samples, out, start, stop):
    """Optical length of each profile [m] from the texels of the transmittance table to the top.

    Fills ``out`` (n_r, n_mu, n_profiles) float64 for flat texel indices ``start..stop``; the optical depth
    is its product with the extinction coefficients at relative density 1.
    """
    n_r, n_mu, n_p = out.shape
    for idx in range(start, stop):
        i_r = idx // n_mu
        i_mu = idx % n_mu
        r, mu = transmittance_params(i_r, i_mu, bottom, top, n_r, n_mu)
        d_end = distance_to_boundary(r, mu, False, bottom, top)
        dx = d_end / n_samples
        for i in range(n_samples + 1):
            d = i * dx
            r_i = math.sqrt(max(d * d + 2.0 * r * mu * d + r * r, 0.0))
            w = 0.5 * dx if (i == 0 or i == n_samples) else dx
            for p in range(n_p):
                out[i_r, i_mu, p] += w * density_at(profiles[p], counts[p], r_i - bottom)


@kernel
def direct_irradiance_kernel(transmittance, bottom, top, alpha, out, start, stop):
    """Direct irradiance on a horizontal surface per unit solar irradiance into ``out`` (n_r, n_mu_s, n_wl).

    The cosine factor is averaged over the solar disc of angular radius ``alpha``: ``mu_s`` above the
    horizon by more than ``alpha``, ``(mu_s + alpha)^2 / (4 alpha)`` while the disc crosses it, else 0.
    """
    n_r, n_mu_s, n_l = out.shape
    t = np.empty(n_l)
    for idx in range(start, stop):
        i_r = idx // n_mu_s
        i_s = idx % n_mu_s
        r, mu_s = irradiance_params(i_r, i_s, bottom, top, n_r, n_mu_s)
        if mu_s < -alpha:
            continue
        cos_factor = mu_s if mu_s > alpha else (mu_s + alpha) * (mu_s + alpha) / (4.0 * alpha)
        transmittance_to_top(transmittance, r, mu_s, bottom, top, t)
        for k in range(n_l):
            out[i_r, i_s, k] = t[k] * cos_factor


@kernel
def texel_nu_kernel(bottom, top, mu_s_min, out, start, stop):
    """The (clamped) view-sun cosine of every texel of the 4D tables, into ``out`` (n_r, n_mu, n_mu_s, n_nu)."""
    n_r, n_mu, n_mu_s, n_nu = out.shape
    mu_s_tab = mu_s_texels(bottom, top, mu_s_min, n_mu_s)
    for idx in range(start, stop):
        i_r = idx // n_mu
        i_mu = idx % n_mu
        _, mu, _ = scattering_r_mu_params(i_r, i_mu, bottom, top, n_r, n_mu)
        for i_s in range(n_mu_s):
            mu_s = mu_s_tab[i_s]
            for i_n in range(n_nu):
                out[i_r, i_mu, i_s, i_n] = scattering_nu_param(i_n, mu, mu_s, n_nu)


#: Nodes of the solar disc's quadrature across its height (:func:`_sun_disc_cells`; the observer's
#: single scattering in twilight, :meth:`.PrecomputedAtmosphere._twilight_singles`: 12 and 24 nodes change it by
#: less than 0.2 %), and the height of the disc's centre above the horizon [disc radii, 0.27 deg each] below which
#: it is used (above: the centre's transmittance, the tables' rule).
DISC_NODES = 6
DISC_HORIZON_RADII = 20.0


@helper(fastmath=CONTRACT_ARCP)
def _sun_transmittance_cells(r, d, r_i, mu_s_flat, nu_flat, bottom, top, alpha, n_tmu, cell, w, frac):
    """Transmittance-table ``mu`` cells and weights towards the sun, and the visible fraction of its disc, at a
    ray sample (distance ``d`` [m] from the texel's point at radius ``r``, radius ``r_i``) for every texel sun
    (``mu_s_flat``, ``nu_flat``, n_mu_s * n_nu): the disc's centre (the stored tables). Its branches are short and
    side-effect free, so the compiler turns them into selects and vectorises the loop (:func:`_sun_disc_cells`,
    with the disc in chords near the horizon, does not: used in place of this one the single-scattering kernel of
    the stored tables took 2.1x the time, measured)."""
    for u in range(mu_s_flat.shape[0]):
        mu_s_i = clamp((r * mu_s_flat[u] + d * nu_flat[u]) / r_i, -1.0, 1.0)
        frac[u] = sun_visible_fraction(r_i, mu_s_i, bottom, alpha)
        _, p_mu = transmittance_coord(r_i, mu_s_i, bottom, top, 2, n_tmu)
        cell[u], w[u] = lerp_index(p_mu, 0, n_tmu - 1)


@helper(fastmath=CONTRACT_ARCP)
def _sun_disc_cells(r, d, r_i, mu_s_flat, nu_flat, bottom, top, alpha, n_tmu, cell, w, frac, disc_x, disc_w):
    """Transmittance-table ``mu`` cells and weights towards the sun, and their shares of its disc, at a ray sample
    (distance ``d`` [m] from the texel's point at radius ``r``, radius ``r_i``) for every texel sun (``mu_s_flat``,
    ``nu_flat``, n_mu_s * n_nu): ``cell``, ``w``, ``frac`` (n_suns * DISC_NODES, the nodes of a sun contiguous),
    unused nodes with share 0.

    Where the disc's centre is at least :data:`DISC_HORIZON_RADII` radii above the horizon, one node: the centre's
    transmittance times the visible fraction (1). Nearer the horizon the transmittance changes across the disc by
    a large factor (a sun ray grazing the Earth 0.27 deg higher passes hundreds of metres to kilometres higher,
    where the air is thinner), and the disc's mean of a convex function is above its centre's value: there the
    visible part of the disc (above the horizon) is cut into horizontal chords at ``DISC_NODES`` Gauss-Legendre
    nodes in the angle ``phi`` of ``u = sin phi`` (``u`` the chord's height in disc radii; the chord's share of the
    disc ``(2 / pi) cos^2 phi dphi``), each chord's sun rays taking the transmittance at their own zenith angle,
    the shares scaled to sum to the visible fraction (:func:`.sampling.sun_visible_fraction`). The Monte Carlo
    draws the disc's points uniformly (docs/montecarlo.md); with the centre alone the observer's single scattering
    in twilight where the views leave the Earth's shadow came out below the Monte Carlo's first order (Earth
    defaults, sun -3 deg, 5 deg up opposite the sun: -78 / -27 / -18 % at 400 / 560 / 700 nm; with the disc within
    its noise at 560 and 700 nm; docs/accuracy.md, "Low sun")."""
    n_k = disc_x.shape[0]
    for u in range(mu_s_flat.shape[0]):
        mu_s_i = clamp((r * mu_s_flat[u] + d * nu_flat[u]) / r_i, -1.0, 1.0)
        f = sun_visible_fraction(r_i, mu_s_i, bottom, alpha)
        sin_h = bottom / r_i
        cos_h = -math.sqrt(max(1.0 - sin_h * sin_h, 0.0))
        h = (mu_s_i - cos_h) / (max(sin_h, 1e-6) * alpha)
        for k in range(n_k):
            frac[u * n_k + k] = 0.0
            cell[u * n_k + k] = 0
            w[u * n_k + k] = 0.0
        if f <= 0.0:
            continue
        if h >= DISC_HORIZON_RADII:
            frac[u * n_k] = f
            _, p_mu = transmittance_coord(r_i, mu_s_i, bottom, top, 2, n_tmu)
            cell[u * n_k], w[u * n_k] = lerp_index(p_mu, 0, n_tmu - 1)
            continue
        theta = math.acos(mu_s_i)
        phi_lo = math.asin(max(-1.0, min(1.0, -h)))
        span = 0.5 * PI - phi_lo
        total = 0.0
        for k in range(n_k):
            phi = phi_lo + span * disc_x[k]
            c = math.cos(phi)
            share = c * c * span * disc_w[k]
            frac[u * n_k + k] = share
            total += share
            mu_k = math.cos(theta - math.sin(phi) * alpha)
            _, p_mu = transmittance_coord(r_i, mu_k, bottom, top, 2, n_tmu)
            cell[u * n_k + k], w[u * n_k + k] = lerp_index(p_mu, 0, n_tmu - 1)
        scale = f / total if total > 0.0 else 0.0
        for k in range(n_k):
            frac[u * n_k + k] *= scale


@inline(fastmath=CONTRACT_ARCP)
def _add_sun(transmittance, j_r, w_tr, j, w, f, w_r32, w_m32, i, u, t_sun, acc_r, acc_m):
    """Sample ``i``'s share of sun ``u``'s single scattering: the transmittance table read at radius cell ``j_r``
    (weight ``w_tr``) and ``mu`` cell ``j`` (weight ``w``) times ``f`` (the visible disc, or a chord's share of it)
    and the sample's ray weights, added to ``acc_r``, ``acc_m`` (float32)."""
    a00, a01, a10, a11 = bilinear_weights(w_tr, w)
    b00, b01, b10, b11 = np.float32(f * a00), np.float32(f * a01), np.float32(f * a10), np.float32(f * a11)
    n_l = t_sun.shape[0]
    # Two loops, not one: each then has few enough possible overlaps between the arrays it writes and reads for the
    # compiler to check them at run time and vectorise it (in one loop it did not, and these loops were most of the
    # single-scattering kernel's time).
    for k in range(n_l):
        t_sun[k] = (b00 * transmittance[j_r, j, k] + b01 * transmittance[j_r, j + 1, k]
                    + b10 * transmittance[j_r + 1, j, k] + b11 * transmittance[j_r + 1, j + 1, k])
    for k in range(n_l):
        acc_r[u, k] += w_r32[i, k] * t_sun[k]
        acc_m[u, k] += w_m32[i, k] * t_sun[k]


@kernel
def single_scattering_kernel(transmittance, bottom, top, mu_s_tab, alpha, profiles, counts, extinction, n_samples,
                             n_r, disc, ray, mie, first_r, start, stop):
    """Single scattering integrals per unit solar irradiance and unit scattering coefficient.

    ``disc``: None for the sun's transmittance at its centre times the visible fraction of its disc (the stored
    tables, :func:`_sun_transmittance_cells`), or (2, n) Gauss-Legendre nodes and weights on [0, 1]
    (:func:`gauss_legendre_unit`) for the disc in ``n`` chords near the horizon (:func:`_sun_disc_cells`,
    :data:`DISC_NODES`: the observer's single scattering in twilight). numba compiles a separate kernel for None,
    without the chords' code: with it in the same compiled kernel the compiler no longer vectorised the centre's
    reads (the stored tables' kernel 1.1-2.6x slower, measured; compiled apart, 0.68-0.74 s of CPU as before).

    Fills ``ray`` and ``mie`` (n_rows, n_mu, n_mu_s, n_nu, n_wavelengths) float32, radius indices ``first_r`` to
    ``first_r + n_rows - 1`` of a table of ``n_r`` radii (a block of rows: the driver streams them), at the sun
    zenith cosines ``mu_s_tab`` (n_mu_s: the tables' texels, :func:`mu_s_texels`, or any others: the rendering
    lookups' sub-texels, :func:`.compute.stored_single_scattering`), for flat (r, mu) indices ``start..stop`` of the
    whole table with
    ``integral rho_i(y) T(x, y) T_sun(y) dy`` from the texel's point to the ground or the top
    (Bruneton & Neyret 2008, Eqs. 9 and 11; the phase functions and coefficients are applied later). ``T(x, y)``
    is integrated along the ray's own samples (:func:`.sampling.ray_transmittance`, ``extinction`` (3, n_wl) the
    Rayleigh, aerosol and ozone extinction at density 1 [m^-1]); ``T_sun`` is read from the table.
    """
    _, n_mu, n_mu_s, n_nu, n_l = ray.shape
    n_pts = n_samples + 1
    dist = np.empty(n_pts)
    rad = np.empty(n_pts)
    rho_r = np.empty(n_pts)
    rho_m = np.empty(n_pts)
    dens = np.empty((n_pts, 3))
    t_view = np.empty((n_pts, n_l))
    w_r = np.empty((n_pts, n_l))
    w_m = np.empty((n_pts, n_l))
    n_tr, n_tmu, _ = transmittance.shape
    n_suns = n_mu_s * n_nu
    # The per-sun loops in float32, like the transmittance table they read and the tables they fill: 8 SIMD lanes
    # instead of 4 (the kernel 20 % faster, 16 wavelengths one thread; the values move by float32 rounding, at
    # most 9e-7 relative)
    acc_r = np.empty((n_suns, n_l), dtype=np.float32)
    acc_m = np.empty((n_suns, n_l), dtype=np.float32)
    w_r32 = np.empty((n_pts, n_l), dtype=np.float32)
    w_m32 = np.empty((n_pts, n_l), dtype=np.float32)
    t_sun = np.empty(n_l, dtype=np.float32)
    nu_flat = np.empty(n_suns)
    n_disc = 1 if disc is None else disc.shape[1]
    cell = np.empty(n_suns * n_disc, dtype=np.int64)  # a sun's disc nodes contiguous
    w_sun = np.empty(n_suns * n_disc)
    frac = np.empty(n_suns * n_disc)
    mu_s_flat = np.repeat(mu_s_tab, n_nu)
    for idx in range(start, stop):
        i_r = idx // n_mu
        i_mu = idx % n_mu
        r, mu, hits = scattering_r_mu_params(i_r, i_mu, bottom, top, n_r, n_mu)
        d_end = distance_to_boundary(r, mu, hits, bottom, top)
        if d_end <= 0.0:
            continue
        for i in range(n_pts):
            d = ray_sample_distance(i, n_samples, d_end, mu, hits)
            dist[i] = d
            rad[i] = point_along_ray(r, mu, d, bottom, top)[0]
            for p in range(3):
                dens[i, p] = density_at(profiles[p], counts[p], rad[i] - bottom)
            rho_r[i] = dens[i, 0]
            rho_m[i] = dens[i, 1]
        ray_transmittance(dist, dens, extinction, t_view)
        # Product integration with density x view transmittance as the exponential factor: at large optical
        # depths the transmittance is far from linear over a step (aerosol optical depth 0.5 seen 70 deg from the
        # zenith falls to 0.4 within the first of 50 steps).
        w_r[:] = 0.0
        w_m[:] = 0.0
        for i in range(n_samples):
            for k in range(n_l):
                fa = rho_r[i] * t_view[i, k]
                fb = rho_r[i + 1] * t_view[i + 1, k]
                ca, cb = exp_segment_weights(fa, fb, dist[i + 1] - dist[i])
                w_r[i, k] += ca * fa
                w_r[i + 1, k] += cb * fb
                fa = rho_m[i] * t_view[i, k]
                fb = rho_m[i + 1] * t_view[i + 1, k]
                ca, cb = exp_segment_weights(fa, fb, dist[i + 1] - dist[i])
                w_m[i, k] += ca * fa
                w_m[i + 1, k] += cb * fb
        for i_s in range(n_mu_s):
            for i_n in range(n_nu):
                nu_flat[i_s * n_nu + i_n] = scattering_nu_param(i_n, mu, mu_s_tab[i_s], n_nu)
        acc_r[:] = 0.0
        acc_m[:] = 0.0
        for i in range(n_pts):
            for k in range(n_l):
                w_r32[i, k] = np.float32(w_r[i, k])
                w_m32[i, k] = np.float32(w_m[i, k])
        for i in range(n_pts):
            if rho_r[i] == 0.0 and rho_m[i] == 0.0:
                continue
            # the transmittance table's r cell is the same for every sun at this sample
            p_r, _ = transmittance_coord(rad[i], 1.0, bottom, top, n_tr, n_tmu)
            j_r, w_tr = lerp_index(p_r, 0, n_tr - 1)
            # The stored tables take the disc's centre (one read per sun), the observer's twilight rows its chords
            # (DISC_NODES reads per sun near the horizon)
            if disc is None:
                _sun_transmittance_cells(r, dist[i], rad[i], mu_s_flat, nu_flat, bottom, top, alpha, n_tmu, cell,
                                         w_sun, frac)
                for u in range(n_suns):
                    if frac[u] > 0.0:
                        _add_sun(transmittance, j_r, w_tr, cell[u], w_sun[u], frac[u], w_r32, w_m32, i, u, t_sun,
                                 acc_r, acc_m)
                continue
            _sun_disc_cells(r, dist[i], rad[i], mu_s_flat, nu_flat, bottom, top, alpha, n_tmu, cell, w_sun, frac,
                            disc[0], disc[1])
            for u in range(n_suns):
                for q in range(u * n_disc, (u + 1) * n_disc):
                    if frac[q] > 0.0:
                        _add_sun(transmittance, j_r, w_tr, cell[q], w_sun[q], frac[q], w_r32, w_m32, i, u, t_sun,
                                 acc_r, acc_m)
        for i_s in range(n_mu_s):
            for i_n in range(n_nu):
                u = i_s * n_nu + i_n
                for k in range(n_l):
                    ray[i_r - first_r, i_mu, i_s, i_n, k] = acc_r[u, k]
                    mie[i_r - first_r, i_mu, i_s, i_n, k] = acc_m[u, k]


@helper
def _quadratic_form(m, vx, vy, vz):
    """v^T m v for a symmetric 3 x 3 matrix."""
    return (m[0, 0] * vx * vx + m[1, 1] * vy * vy + m[2, 2] * vz * vz
            + 2.0 * (m[0, 1] * vx * vy + m[0, 2] * vx * vz + m[1, 2] * vy * vz))


@helper
def gauss_legendre_unit(n, x, w):
    """Gauss-Legendre nodes ``x`` and weights ``w`` (n each, ascending) on [0, 1] ([Abramowitz1964] 25.4.29,
    nodes the zeros of the Legendre polynomial ``P_n``, weights ``2 / ((1 - z^2) P_n'(z)^2)`` on [-1, 1]), by
    Newton's iteration: here, not numpy's ``leggauss``, because the kernels build their grids inside numba."""
    for i in range(n):
        z = math.cos(PI * (i + 0.75) / (n + 0.5))
        dp = 1.0
        for _ in range(100):
            p0 = 1.0
            p1 = z
            for k in range(2, n + 1):
                p0, p1 = p1, ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k
            dp = n * (z * p1 - p0) / (z * z - 1.0)
            dz = p1 / dp
            z -= dz
            if abs(dz) < 1e-15:
                break
        x[n - 1 - i] = 0.5 * (z + 1.0)
        w[n - 1 - i] = 1.0 / ((1.0 - z * z) * dp * dp)


@kernel
def sphere_quadrature(n_theta, hemisphere):
    """Directions and solid angles [sr] on the sphere (or upper hemisphere), in a frame whose x axis points to
    the sun's azimuth: (n_theta * 2 n_theta, 3) directions and their weights.

    Zenith: double Gauss, Gauss-Legendre in ``cos theta`` on each hemisphere separately (``n_theta / 2`` nodes
    each on the sphere, the upper one more if ``n_theta`` is odd; ``n_theta`` on the upper hemisphere), the rule
    of discrete-ordinate solvers because the radiance is discontinuous at the horizon ([Stamnes1988]): nodes
    crowd towards the horizon, where the radiance of a low sun in haze peaks, and towards the zenith. With 16
    zenith steps the nodes nearest the horizon are at +-1.1 deg instead of the midpoint rule's +-5.6 deg; the
    hazy low-sun sky 2 deg above the horizon towards the sun came out 21 -> 9 % above the Monte Carlo (sun
    +0.8 deg; docs/accuracy.md, "Low sun"), and 32 steps of either rule change it by less than 1.5 %.
    Azimuth: the midpoint rule."""
    n_phi = 2 * n_theta
    d_phi = 2.0 * PI / n_phi
    n_up = n_theta if hemisphere else n_theta - n_theta // 2
    n_lo = n_theta - n_up
    ux = np.empty(n_up)
    uw = np.empty(n_up)
    lx = np.empty(n_lo)
    lw = np.empty(n_lo)
    gauss_legendre_unit(n_up, ux, uw)
    gauss_legendre_unit(n_lo, lx, lw)
    om = np.empty((n_theta * n_phi, 3))
    dom = np.empty(n_theta * n_phi)
    for i in range(n_theta):
        # the upper hemisphere from the zenith down, then the lower one from the horizon down
        if i < n_up:
            ct = ux[n_up - 1 - i]
            wt = uw[n_up - 1 - i]
        else:
            ct = -lx[i - n_up]
            wt = lw[i - n_up]
        st = math.sqrt(max(1.0 - ct * ct, 0.0))
        for j in range(n_phi):
            phi = (j + 0.5) * d_phi
            w = i * n_phi + j
            om[w, 0] = st * math.cos(phi)
            om[w, 1] = st * math.sin(phi)
            om[w, 2] = ct
            dom[w] = wt * d_phi
    return om, dom


@kernel
def mirror_pairs(n_theta):
    """The mirrored pairs of :func:`sphere_quadrature`'s directions about the sun's vertical plane (x-z): two
    (n_theta * n_theta,) index arrays, each pair's first direction (azimuths 0 to pi, j < n_theta of a zenith row's
    2 n_theta midpoints) and its mirror image (2 n_theta - 1 - j). The incident radiance of the scattering density
    and of the irradiance is symmetric about that plane, so each pair is read once (table format 22)."""
    n_phi = 2 * n_theta
    first = np.empty(n_theta * n_theta, dtype=np.int64)
    mirror = np.empty(n_theta * n_theta, dtype=np.int64)
    for i in range(n_theta):
        for j in range(n_theta):
            first[i * n_theta + j] = i * n_phi + j
            mirror[i * n_theta + j] = i * n_phi + n_phi - 1 - j
    return first, mirror


@kernel(fastmath=CONTRACT_REASSOC)
def scattering_density_kernel(transmittance, s_a, s_b, first, ground_irradiance, albedo, beta_r, beta_m, g, mie_kind,
                              lobe, phase_mu, phase_full, phase_trunc, profiles, counts, bottom, top, mu_s_min, n_theta,
                              out, first_r, start, stop):
    """Scattering density J (Eq. 7) of one order per unit total scattering coefficient, ``J / (beta_R rho_R(r) +
    beta_M rho_M(r))`` at each texel's radius, into ``out`` (n_rows, n_mu, n_mu_s, n_nu, n_wl) float32 (radius
    indices ``first_r`` to ``first_r + n_rows - 1``: a block of rows), for radius indices ``start..stop``: the
    incident radiance weighted by the Rayleigh and the aerosol phase functions in the proportions of the two
    scattering coefficients there.

    Stored per unit scattering coefficient because the densities fall exponentially with altitude (the aerosols'
    scale height is 1.2 km) while this weighted radiance varies slowly: :func:`multiple_scattering_kernel`
    interpolates it between table radii and multiplies by the exact coefficient at each ray sample. Interpolating
    J itself overestimated it between radii (linear interpolation of a convex exponential): +5 to +7 % in the
    converged multiple scattering of an aerosol optical depth of 0.5 against DISORT with 16 radii (docs/bruneton.md).
    Keeping the Rayleigh and aerosol parts apart (two tables, exact coefficients for each) agreed with this
    within 0.6 % there and made the multiple-scattering kernel 13 % slower.

    The incident radiance is the previous order: ``s_a P_R + s_b P_M`` (single Rayleigh and Mie tables, read along
    the azimuth with the shadow-following weights of :func:`.sampling.scattering_lookup_shadow`, factors up to
    :data:`.sampling.SHADOW_RATIO_MAX` since table format 21) when ``first``, else the table ``s_a`` (multiple
    scattering, phase included, stored divided by :func:`.sampling.multiple_lobe` of weight ``lobe``: read as
    ``s_a F(nu)``); plus, for directions that
    meet the ground, the ground's reflection of ``ground_irradiance`` (Eqs. 6 and 10, Lambertian ``albedo``).
    The sphere is sampled with ``n_theta x 2 n_theta`` midpoint directions in a frame whose x axis points to
    the sun's azimuth; for each view direction the phase-function weights are normalised to integrate to one
    on that grid, so a uniform radiance field is scattered without loss or gain of energy even where the
    forward Mie peak is under-resolved. The Rayleigh phase is a quadratic in ``v . w``, so its integral is
    ``3 / (16 pi) (M0 + v^T M2 v)`` with the radiance moments ``M0 = sum L dw`` and ``M2 = sum w w^T L dw``:
    exact on the grid and without a loop per view. The incident radiance and the grid are symmetric about the
    sun's vertical plane (x-z), so each mirrored pair of grid directions is read once and scattered with the sum of
    its two phase values, and the moments' xy and yz components vanish (table format 22: half the reads and half
    the product; the density within float32 rounding of the whole grid's, at most 9e-6 relative, measured).

    The view direction of texel (mu, nu) in that frame is ``(sin theta cos phi, sin theta sin phi, mu)`` with
    ``phi`` the texel's view-sun azimuth (:func:`.geometry.scattering_nu_azimuth`), the same for every sun
    zenith; so the aerosol phase between every texel's view and every quadrature direction is one matrix per
    radius, and the Mie part of J for all sun zeniths and wavelengths is one matrix product (BLAS, in single
    precision: float32 copies of both operands; the phase's normalisation sums the same rounded values in float64)
    with the quadrature radiance.

    A tabulated aerosol phase (``mie_kind`` :data:`.sampling.TABLE_PHASE`; ``phase_mu`` (n,) ascending cosines,
    ``phase_full`` (n_wl, n) the phase table that the first order's single-scattered light is weighted with,
    ``phase_trunc`` (n_wl, n_u) the phase the density scatters with, sampled at ``n_u`` cosines evenly spaced from
    -1 to 1: one index per direction pair instead of a search) is always the delta-M scaled medium's
    (:meth:`.compute.Medium.delta_m_scaled`): both are the truncated ``p*``, a Legendre series smooth on the
    quadrature, and the forward peak is not scattered here at all (it is in the scaled extinction). Until table
    format 11 the density scattered the unscaled medium's light with ``(1 - f) p*`` on the grid plus the delta
    ``f L(v)`` exactly: the texel's own incident radiance, whose first order carries the full table's diffraction
    peak, went into the density table, and the next order's ray integral interpolated that peak linearly in the
    view-sun axis; with sea salt (OPAC sscm, AOD 0.2-0.5) the diffuse irradiance came out up to 38 % above DISORT
    (docs/aerosols.md).
    """
    n_r, n_mu, n_s, n_n, n_l = s_a.shape
    table = mie_kind == TABLE_PHASE
    om, dom = sphere_quadrature(n_theta, False)
    n_om = om.shape[0]
    n_v = n_mu * n_n
    inv_pi = 1.0 / PI
    # The incident radiance is symmetric about the sun's vertical plane (the x-z plane of the quadrature's frame):
    # each read takes the direction's height and view-sun cosine, the ground's reflection its x and z, none its y.
    # The azimuth grid is symmetric too (the midpoints j and 2 n_theta - 1 - j mirror each other), so each pair of
    # mirrored directions is read once and scattered with the sum of the two phase values: half the reads and half
    # the product's terms (the y moments of the Rayleigh sums vanish)
    pair_a, pair_b = mirror_pairs(n_theta)
    n_h = pair_a.shape[0]
    # per direction pair, the (sun zenith, wavelength) radiances contiguous: the product below then gives each view's
    # values over the suns and wavelengths contiguous, and the final loop runs over the wavelengths on SIMD lanes
    # (the phase per view and direction pair, phase_m, transposed to match)
    radiance = np.zeros((n_h, n_s * n_l))
    # the analytic phase's product in single precision (SGEMM): 3-7 % less CPU for the whole default precompute,
    # the tables change by float32 rounding (docs/bruneton.md); its operands are float32 copies, the sums around it
    # stay float64
    radiance32 = np.zeros((n_h, n_s * n_l), dtype=np.float32)
    phase_m = np.empty((n_v, n_h), dtype=np.float32)
    # tabulated phase: per wavelength (empty otherwise)
    n_lt = n_l if table else 0
    # one wavelength's truncated phase at a time (n_h, n_v), filled just before its product: a table of all
    # wavelengths was n_l times larger (67 MB at 16 wavelengths and default sizes) and written then read back
    phase_t = np.empty((n_h if table else 0, n_v), dtype=np.float32)
    # the cells of each direction pair's two cosines on that grid, the same for every wavelength: found once per
    # radius
    cell_i = np.empty((2, n_h if table else 0, n_v), dtype=np.int32)
    cell_f = np.empty((2, n_h if table else 0, n_v))
    norm_t = np.empty((n_lt, n_v))
    mie_t = np.empty((n_lt, n_s, n_v))
    rad_k = np.empty((n_s, n_h), dtype=np.float32)
    n_u = phase_trunc.shape[1]
    half_u = 0.5 * (n_u - 1)
    view_x = np.empty(n_v)  # the view directions' components apart: contiguous for the phase fill
    view_y = np.empty(n_v)
    view_z = np.empty(n_v)
    pv = np.empty(n_l)
    tmp2 = np.empty(n_l)
    view = np.empty((n_v, 3))
    norm_m = np.empty(n_v)
    norm_r = np.empty(n_v)
    m_acc = np.empty(n_l)  # a view's aerosol part per wavelength
    buf = np.empty(n_l)
    e_buf = np.empty(n_l)
    t_buf = np.empty(n_l)
    tmp = np.empty(n_l)
    columns = np.empty((4, n_l))  # scratch of the previous order's read (sampling.scattering_lookup)
    # Moments of the quadrature weights (normalisation of the Rayleigh phase on the grid).
    w0 = 0.0
    w2 = np.zeros((3, 3))
    for w in range(n_om):
        w0 += dom[w]
        for a in range(3):
            for b in range(3):
                w2[a, b] += om[w, a] * om[w, b] * dom[w]
    m0 = np.zeros((n_s, n_l))
    # the second moments' components that do not vanish by the symmetry (xx, yy, zz, xz), each contiguous over the
    # wavelengths
    m2 = np.zeros((n_s, 4, n_l))
    f_r = np.empty(n_l)
    f_m = np.empty(n_l)
    mu_s_tab = mu_s_texels(bottom, top, mu_s_min, n_s)
    for i_r in range(start, stop):
        r, _, _ = scattering_r_mu_params(i_r, n_mu // 2, bottom, top, n_r, n_mu)
        for i_mu in range(n_mu):
            _, mu, _ = scattering_r_mu_params(i_r, i_mu, bottom, top, n_r, n_mu)
            st = math.sqrt(max(1.0 - mu * mu, 0.0))
            for i_n in range(n_n):
                phi = scattering_nu_azimuth(i_n, n_n)
                v = i_mu * n_n + i_n
                vx = st * math.cos(phi)
                vy = st * math.sin(phi)
                view[v, 0] = vx
                view[v, 1] = vy
                view[v, 2] = mu
                view_x[v] = vx
                view_y[v] = vy
                view_z[v] = mu
                if not table:
                    nm = 0.0
                    for h in range(n_h):
                        a = pair_a[h]
                        b = pair_b[h]
                        pm = np.float32(aerosol_phase(vx * om[a, 0] + vy * om[a, 1] + mu * om[a, 2], g, mie_kind)
                                        + aerosol_phase(vx * om[b, 0] + vy * om[b, 1] + mu * om[b, 2], g, mie_kind))
                        phase_m[v, h] = pm
                        nm += pm * dom[a]  # of the rounded values the product uses: energy kept to float64
                    norm_m[v] = nm
                norm_r[v] = w0 + _quadratic_form(w2, vx, vy, mu)
        m0[:] = 0.0
        m2[:] = 0.0
        for i_s in range(n_s):
            mu_s = mu_s_tab[i_s]
            sx = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
            for h in range(n_h):
                w = pair_a[h]
                wx = om[w, 0]
                wy = om[w, 1]
                wz = om[w, 2]
                nu_w = clamp(wx * sx + wz * mu_s, -1.0, 1.0)
                hits = ray_hits_ground(r, wz, bottom)
                for k in range(n_l):
                    buf[k] = 0.0
                if first:
                    # the single scattering along the azimuth follows the Earth's shadow (sampling.shadow_nu_weights)
                    scattering_lookup_shadow(s_a, r, wz, mu_s, nu_w, hits, bottom, top, mu_s_min,
                                             rayleigh_phase(nu_w), profiles[0], counts[0], buf)
                    if table:
                        for k in range(n_l):
                            tmp2[k] = 0.0
                        scattering_lookup_shadow(s_b, r, wz, mu_s, nu_w, hits, bottom, top, mu_s_min, 1.0,
                                                 profiles[1], counts[1], tmp2)
                        phase_table_values(phase_mu, phase_full, nu_w, pv)
                        for k in range(n_l):
                            buf[k] += pv[k] * tmp2[k]
                    else:
                        scattering_lookup_shadow(s_b, r, wz, mu_s, nu_w, hits, bottom, top, mu_s_min,
                                                 aerosol_phase(nu_w, g, mie_kind), profiles[1], counts[1], buf)
                else:
                    scattering_lookup(s_a, r, wz, mu_s, nu_w, hits, bottom, top, mu_s_min,
                                      multiple_lobe(nu_w, lobe), buf, columns)
                if hits:
                    d_g = distance_to_bottom(r, wz, bottom)
                    mu_s_g = clamp((d_g * wx * sx + (r + d_g * wz) * mu_s) / bottom, -1.0, 1.0)
                    irradiance_lookup(ground_irradiance, bottom, mu_s_g, bottom, top, e_buf)
                    transmittance_segment(transmittance, r, wz, d_g, True, bottom, top, t_buf, tmp)
                    for k in range(n_l):
                        buf[k] += t_buf[k] * albedo[k] * inv_pi * e_buf[k]
                # the pair's two directions in the moments: twice one's (their y moments cancel)
                oxx, oyy, ozz, oxz = 2.0 * wx * wx, 2.0 * wy * wy, 2.0 * wz * wz, 2.0 * wx * wz
                for k in range(n_l):
                    lw = buf[k] * dom[w]
                    radiance[h, i_s * n_l + k] = lw
                    m0[i_s, k] += 2.0 * lw
                    m2[i_s, 0, k] += oxx * lw
                    m2[i_s, 1, k] += oyy * lw
                    m2[i_s, 2, k] += ozz * lw
                    m2[i_s, 3, k] += oxz * lw
        if table:
            for h in range(n_h):
                for e in range(2):
                    w = pair_a[h] if e == 0 else pair_b[h]
                    ox, oy, oz = om[w, 0], om[w, 1], om[w, 2]
                    for v in range(n_v):
                        x = (min(max(view_x[v] * ox + view_y[v] * oy + view_z[v] * oz, -1.0), 1.0) + 1.0) * half_u
                        i = min(int(x), n_u - 2)
                        cell_i[e, h, v] = i
                        cell_f[e, h, v] = x - i
            for k in range(n_l):
                for v in range(n_v):
                    norm_t[k, v] = 0.0
                pk = phase_trunc[k]
                for h in range(n_h):
                    dw = dom[pair_a[h]]
                    for v in range(n_v):
                        i, f = cell_i[0, h, v], cell_f[0, h, v]
                        i2, f2 = cell_i[1, h, v], cell_f[1, h, v]
                        p = np.float32((1.0 - f) * pk[i] + f * pk[i + 1] + (1.0 - f2) * pk[i2] + f2 * pk[i2 + 1])
                        phase_t[h, v] = p
                        norm_t[k, v] += p * dw  # of the rounded values the product uses, as for an analytic phase
                for i_s in range(n_s):
                    for h in range(n_h):
                        rad_k[i_s, h] = radiance[h, i_s * n_l + k]
                # (n_s, n_v): sum over quadrature directions of L dw p*, in single precision like the analytic
                # phase's product (SGEMM)
                mie_t[k] = np.dot(rad_k, phase_t)
            mie = phase_m[:0]
        else:
            radiance32[:] = radiance
            mie = np.dot(phase_m, radiance32)  # (n_v, n_s n_l): sum over quadrature directions of L dw P_M
        rho_r = density_at(profiles[0], counts[0], r - bottom)
        rho_m = density_at(profiles[1], counts[1], r - bottom)
        for k in range(n_l):
            b_tot = beta_r[k] * rho_r + beta_m[k] * rho_m
            f_r[k] = beta_r[k] * rho_r / b_tot if b_tot > 0.0 else 0.0
            f_m[k] = beta_m[k] * rho_m / b_tot if b_tot > 0.0 else 0.0
        for i_s in range(n_s):
            sx_s = math.sqrt(max(1.0 - mu_s_tab[i_s] * mu_s_tab[i_s], 0.0))
            for i_mu in range(n_mu):
                for i_n in range(n_n):
                    v = i_mu * n_n + i_n
                    vx, vy, vz = view[v, 0], view[v, 1], view[v, 2]
                    # stored divided by the lobe at the texel's own view-sun cosine (the sun at azimuth 0)
                    inv_lobe = 1.0 / multiple_lobe(clamp(vx * sx_s + vz * mu_s_tab[i_s], -1.0, 1.0), lobe)
                    if table:
                        for k in range(n_l):
                            m_acc[k] = mie_t[k, i_s, v] / norm_t[k, v]
                    else:
                        inv_m = 1.0 / norm_m[v]
                        for k in range(n_l):
                            m_acc[k] = mie[v, i_s * n_l + k] * inv_m
                    # the Rayleigh part: v^T M2 v (_quadratic_form's value) from the moments that do not vanish
                    pxx, pyy, pzz, pxz = vx * vx, vy * vy, vz * vz, 2.0 * vx * vz
                    inv_r = 1.0 / norm_r[v]
                    for k in range(n_l):
                        acc_r = (m0[i_s, k] + pxx * m2[i_s, 0, k] + pyy * m2[i_s, 1, k] + pzz * m2[i_s, 2, k]
                                 + pxz * m2[i_s, 3, k])
                        out[i_r - first_r, i_mu, i_s, i_n, k] = (f_r[k] * acc_r * inv_r + f_m[k] * m_acc[k]) * inv_lobe


@helper
def _hemisphere_irradiance(s_a, s_b, first, lobe, phase_trunc, forward, r, mu_s, bottom, top, mu_s_min, om, dom,
                           half, acc, tmp, columns):
    """``acc = E[L](r, mu_s)``: the sum of :func:`indirect_irradiance_kernel` over the upper hemisphere's
    directions ``om`` (solid angles ``dom``) at radius ``r`` [m] and sun zenith cosine ``mu_s``, the first order's
    forward delta included (``acc``, ``tmp`` (n_wavelengths,) and ``columns`` (4, n_wavelengths) scratch).

    Only the directions ``half`` (indices into ``om``: the azimuths on the positive-y side of the sun's vertical
    plane) are read, each counted twice: the radiance is symmetric about that plane (each read takes the
    direction's height and view-sun cosine), and so is the azimuth grid (:func:`scattering_density_kernel`)."""
    n_l = acc.shape[0]
    n_r, n_mu, n_s, n_n, _ = s_a.shape
    n_u = phase_trunc.shape[1]
    half_u = 0.5 * (n_u - 1)
    sx = math.sqrt(max(1.0 - mu_s * mu_s, 0.0))
    acc[:] = 0.0
    # The reads of :func:`.sampling.scattering_lookup`, with the geometry that does not change between directions
    # computed once: the sun zenith cell for the whole hemisphere, the (r, mu) cell per zenith row of the quadrature
    # (its directions are stored row by row). Recomputing both per direction was most of this kernel's time (the
    # same values: the same helpers on the same arguments).
    i_s, w_s = lerp_index(scattering_mu_s_coord(mu_s, bottom, top, mu_s_min, n_s), 0, n_s - 1)
    wz_row = math.nan
    i_r, w_r, i_m0, w_m0, i_m1, w_m1 = 0, 0.0, 0, 0.0, 0, 0.0
    for h in range(half.shape[0]):
        w = half[h]
        wz = om[w, 2]
        if wz != wz_row:
            i_r, w_r, i_m0, w_m0, i_m1, w_m1 = r_mu_cell(r, wz, False, bottom, top, n_r, n_mu)
            wz_row = wz
        nu_w = clamp(om[w, 0] * sx + wz * mu_s, -1.0, 1.0)
        i_n, w_n = lerp_index(scattering_nu_coord(wz, mu_s, nu_w, n_n), 0, n_n - 1)
        scale = 2.0 * wz * dom[w]  # the direction and its mirror image
        if first:
            lookup4_cell_weighted(s_a, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, 1.0 - w_n, w_n,
                                  scale * rayleigh_phase(nu_w), acc)
            tmp[:] = 0.0
            lookup4_cell_weighted(s_b, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, 1.0 - w_n, w_n, scale, tmp)
            x = (nu_w + 1.0) * half_u
            i = min(int(x), n_u - 2)
            t = x - i
            for k in range(n_l):
                p = (1.0 - t) * phase_trunc[k, i] + t * phase_trunc[k, i + 1]
                acc[k] += (1.0 - forward[k]) * p * tmp[k]
        else:
            # the multiple scattering is stored divided by its lobe (.sampling.multiple_lobe)
            lookup4_cell_weighted(s_a, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, 1.0 - w_n, w_n,
                                  scale * multiple_lobe(nu_w, lobe), acc)
    if first and mu_s > 0.0:
        # the forward delta: the single-scattered aerosol light along the sun's own direction
        tmp[:] = 0.0
        scattering_lookup(s_b, r, mu_s, mu_s, 1.0, False, bottom, top, mu_s_min, mu_s, tmp, columns)
        for k in range(n_l):
            acc[k] += forward[k] * tmp[k]


@kernel
def indirect_irradiance_kernel(s_a, s_b, first, g, mie_kind, lobe, phase_trunc, forward, bottom, top, mu_s_min, n_theta,
                               out, start, stop):
    """Irradiance on a horizontal surface from one order of sky radiance (Eq. 15) into ``out`` (n_r, n_mu_s,
    n_wl).

    Radiance is ``s_a P_R + s_b P_M`` when ``first`` (single scattering) else ``s_a`` times
    :func:`.sampling.multiple_lobe` of weight ``lobe`` (the multiple scattering is stored divided by it); upper
    hemisphere sampled with ``n_theta x 2 n_theta`` directions (:func:`sphere_quadrature`).

    The aerosol phase, tabulated or analytic (``phase_trunc``, ``forward`` as in
    :func:`scattering_density_kernel`; an analytic phase's from its formula tabulated, :func:`.compute.
    aerosol_phase_arrays`; ``g`` and ``mie_kind`` are not used here), is split as there ([Wiscombe1977] Eqs.
    5-7, delta-M): ``P_M = (1 - f) p* + f delta(1 - nu) / (2 pi)``. A coarse mode's diffraction peak is a few
    degrees wide and the quadrature's azimuths are midpoints (never the sun's), so summing the full table on the
    grid missed the aureole: the first order came out 13-30 % low for waso 0.15 + sscm 0.10 at the retrieval's
    sizes (tests/test_precomputed_irradiance.py); the default Cornette-Shanks phase (g = 0.8) the same way, by
    several per cent. The aerosol part of the first order's ``E[L*]`` ([Bruneton2008] Eq. 15 with the
    single-scattered ``L*`` of Eq. 11, ``S_M(r, mu, mu_s, nu) P_M(nu)``) is then ``(1 - f) sum_w S_M(w) p*(nu_w)
    w_z dw`` on the grid (``p*`` a ``2 x density_sphere_samples``-term Legendre series, smooth on it) plus the
    delta part exactly: the delta picks the sun's own direction, ``f mu_s S_M(r, mu_s, mu_s, 1)`` (for ``mu_s >
    0``: a sun below the horizon puts no forward peak on a horizontal surface). The higher orders' radiance
    ``s_a`` is summed on the grid as it is. A tabulated phase comes here as the delta-M scaled medium's (table
    format 11, :meth:`.compute.Medium.delta_m_scaled`: ``p*`` and ``f = 0``; its peak's light is the scaled
    direct beam's excess, which :func:`.compute._orders` adds to the irradiance table), so the split above serves
    the analytic phases.

    A texel whose sun is below the horizon (``mu_s < 0``) comes from the hemisphere sums at the scattering tables'
    three sun zenith texels nearest its ``mu_s`` (:func:`.geometry.scattering_mu_s_param`, where the reads are
    exact along ``mu_s``), their logarithms interpolated quadratically (Lagrange) in the sun elevation and the result
    kept between the two texels around it (log-linear between those two where a sum is zero). The sum at the
    texel's own ``mu_s`` read each direction's radiance linearly between those texels, across which the twilight sky
    falls by up to 30 times (turbidity 3, 560 nm: -7.6 to -5.9 deg): +66 % at -6.4 deg and +14 % at -4.6 deg
    against the hemisphere integral of the independent single scattering of ``benchmarks/second_order_low_sun.py``;
    each direction read log-linearly along mu_s instead: -40 % and -10 % (a sum of geometric interpolations is
    below the geometric interpolation of the sum); the sums at two texels log-linear in the index position: -23 %
    and -8 % (the logarithm falls faster the lower the sun). At the texels themselves the sums are within 1.6 % of
    the integral, and the log-quadratic rule within 1.8 % between them (docs/accuracy.md, "Low sun").
    """
    n_r, n_mu_s, n_l = out.shape
    om, dom = sphere_quadrature(n_theta, True)
    half, _ = mirror_pairs(n_theta)  # each pair's first direction, counted twice (_hemisphere_irradiance)
    n_s = s_a.shape[2]
    acc = np.zeros(n_l)
    sums = np.zeros((3, n_l))
    tmp = np.empty(n_l)
    columns = np.empty((4, n_l))
    # the hemisphere sums at the scattering tables' sun zenith texels, per radius: neighbouring texels below the
    # horizon share two or three of their three (computed once: the same values)
    at_texel = np.empty((n_r, n_s, n_l))
    have = np.zeros((n_r, n_s), dtype=np.bool_)
    for idx in range(start, stop):
        i_r = idx // n_mu_s
        i_s = idx % n_mu_s
        r, mu_s = irradiance_params(i_r, i_s, bottom, top, n_r, n_mu_s)
        if mu_s < mu_s_min:
            continue
        if mu_s >= 0.0 or n_s < 3:
            _hemisphere_irradiance(s_a, s_b, first, lobe, phase_trunc, forward, r, mu_s, bottom, top, mu_s_min, om, dom,
                                   half, acc, tmp, columns)
        else:
            # below the horizon: the sums at the scattering tables' three sun zenith texels nearest mu_s (where their
            # reads are exact along mu_s), log-quadratic in the sun elevation between them
            j, w_s = lerp_index(scattering_mu_s_coord(mu_s, bottom, top, mu_s_min, n_s), 0, n_s - 1)
            j0 = min(max(j - 1 if w_s < 0.5 else j, 0), n_s - 3)
            for q in range(3):
                if not have[i_r, j0 + q]:
                    mu_q = scattering_mu_s_param(j0 + q, bottom, top, mu_s_min, n_s)
                    _hemisphere_irradiance(s_a, s_b, first, lobe, phase_trunc, forward, r, mu_q, bottom, top, mu_s_min,
                                           om, dom, half, acc, tmp, columns)
                    at_texel[i_r, j0 + q, :] = acc
                    have[i_r, j0 + q] = True
                sums[q, :] = at_texel[i_r, j0 + q, :]
            a0 = math.asin(scattering_mu_s_param(j0, bottom, top, mu_s_min, n_s))
            a1 = math.asin(scattering_mu_s_param(j0 + 1, bottom, top, mu_s_min, n_s))
            a2 = math.asin(scattering_mu_s_param(j0 + 2, bottom, top, mu_s_min, n_s))
            a = math.asin(mu_s)
            l0 = (a - a1) * (a - a2) / ((a0 - a1) * (a0 - a2))
            l1 = (a - a0) * (a - a2) / ((a1 - a0) * (a1 - a2))
            l2 = (a - a0) * (a - a1) / ((a2 - a0) * (a2 - a1))
            c = j - j0  # the cell (j, j + 1) around mu_s among the three
            for k in range(n_l):
                e_a, e_b = sums[c, k], sums[c + 1, k]
                if sums[0, k] > 0.0 and sums[1, k] > 0.0 and sums[2, k] > 0.0:
                    e = math.exp(l0 * math.log(sums[0, k]) + l1 * math.log(sums[1, k]) + l2 * math.log(sums[2, k]))
                    acc[k] = min(max(e, min(e_a, e_b)), max(e_a, e_b))
                else:
                    acc[k] = e_a + log_lerp_weight(e_a, e_b, w_s) * (e_b - e_a)
        for k in range(n_l):
            out[i_r, i_s, k] = acc[k]


#: The multiple-scattering kernel's per-sun loops over the wavelengths run on SIMD lanes only for whole groups of
#: 4 (the compiler's vectorised tail handles 4 at a time): 3 wavelengths ran as scalar code, 1.80 s of CPU per
#: order against 1.23-1.32 s for 4 and 1.57 s for 16 (default sizes, one thread, 4 of the 32 radii times 8;
#: 2026-12-06), so the loops run over the wavelengths padded with zero values to a multiple of 4 (3 -> 1.28 s; the
#: padding's sums are never stored). A fixed inner loop of 8 instead ran 4x slower (not vectorised).
WAVELENGTH_PAD = 4

#: Sun elevation [rad] of the lower texel of a sun-zenith cell from which the orders' ray integral reads the
#: scattering density linearly along the sun zenith; below it log-linearly (:func:`multiple_scattering_kernel`).
#: The density falls by orders of magnitude between sun-zenith texels only where the sun sets for the sample, in
#: twilight and near the horizon; with the lower texel at +6 deg or more the two reads differ by at most 0.21 % in the
#: sky (400 / 560 / 700 nm, Earth defaults, turbidity 3, optical depth 0.5; observers at 0 / 2 / 10 / 40 km, views
#: -10 to +88 deg, suns +60 to -6 deg; 2026-12-06), and the linear read costs no square root or division per sun
#: and wavelength (the kernel 0.155 -> 0.136 s, one thread, 4 of 32 radii). With the lower texel from +3.25 deg up
#: the difference was up to 1.0 % (suns near +3 deg): not taken.
LOG_SUN_ZENITH_BELOW = math.radians(6.0)


@helper(fastmath=CONTRACT_ARCP)
def _sun_cells(r, d, r_i, mu_i, mu_s_flat, nu_flat, bottom, top, mu_s_min, big_a, theta_max, n_s, n_n, j_log, cell,
               w_s, w_n, steep):
    """(mu_s, nu) cells and weights at a ray sample (distance ``d`` [m] from the texel's point at radius ``r``,
    radius ``r_i``, view zenith cosine ``mu_i`` there) for every texel sun (``mu_s_flat``, ``nu_flat``: the
    texel's sun zenith and view-sun cosines, n_s * n_n); ``cell`` -1 where the sun at the sample is beyond the
    tables' limit; ``steep`` where the cell's lower sun-zenith texel is below ``j_log`` (read log-linearly). Branch-
    free apart from selects: the compiler vectorises it (the sun coordinates were most of the multiple-scattering
    time)."""
    for u in range(mu_s_flat.shape[0]):
        nu = nu_flat[u]
        mu_s_i = (r * mu_s_flat[u] + d * nu) / r_i
        # A texel whose sun is at the limit (mu_s_min) has samples there to rounding: keep them all.
        ok = mu_s_i >= mu_s_min - MU_S_LIMIT_TOLERANCE
        mu_s_i = min(max(mu_s_i, mu_s_min), 1.0)
        j_s, ws = lerp_index(scattering_mu_s_coord_a(mu_s_i, bottom, top, big_a, theta_max, n_s), 0, n_s - 1)
        j_n, wn = lerp_index(scattering_nu_coord(mu_i, mu_s_i, nu, n_n), 0, n_n - 1)
        cell[u] = j_s * n_n + j_n if ok else -1
        steep[u] = j_s < j_log
        w_s[u] = ws
        w_n[u] = wn


@kernel
def multiple_scattering_kernel(transmittance, density, beta_r, beta_m, profiles, counts, extinction, bottom, top,
                               mu_s_min, n_samples, out, first_r, start, stop):
    """Radiance of one order scattered towards each texel's point (Eq. 11 with the order's J) into ``out``
    (float32, like the densities; radius indices ``first_r`` to ``first_r + n_rows - 1``, a block of rows), for
    flat (r, mu) indices ``start..stop`` of the whole table.

    ``integral T(x, y) J(y, v, s) dy`` from the point to the ground or the top, by product integration
    with the total scattering coefficient ``beta_r rho_r + beta_m rho_m`` as the exponential factor; at each
    sample ``J = (beta_R rho_R(y) + beta_M rho_M(y)) density`` with the exact coefficient at the sample and the
    density per unit scattering coefficient of :func:`scattering_density_kernel` interpolated: linearly in r, mu
    and the view-sun azimuth, and along the sample's sun zenith log-linearly in the cells whose lower texel has the
    sun below :data:`LOG_SUN_ZENITH_BELOW` (:func:`.geometry.log_lerp_weight` of each wavelength's own values, so
    the tables do not depend on the wavelength chunking), linearly above. Along a ray at twilight the sun sets for
    the samples one after another and the density falls by orders of magnitude from one sun-zenith texel to the
    next; a linear interpolation of that fall made the multiple scattering of clear air at a sun 6 deg below the
    horizon 11-66 % too bright against the Monte Carlo (docs/accuracy.md, "Low sun"). Along the azimuth the density
    is stored divided by the aerosol's lobe (format 19), which leaves it smooth: the log-linear read there (until
    2026-12-06) and the linear one differ by at most 0.12 % in the sky (the cases of :data:`LOG_SUN_ZENITH_BELOW`),
    and the linear one spares a square root and a division per sun and wavelength (the kernel 0.181 -> 0.155 s, one
    thread, 4 of 32 radii; 2026-12-06). ``T(x, y)`` is integrated
    along the ray's samples (:func:`.sampling.ray_transmittance`; ``extinction`` as for
    :func:`single_scattering_kernel`); ``transmittance``
    is unused here and kept for the common signature.
    """
    n_r, n_mu, n_s, n_n, n_l = density.shape
    n_pts = n_samples + 1
    dist = np.empty(n_pts)
    rad = np.empty(n_pts)
    cell_ir = np.empty(n_pts, dtype=np.int64)
    cell_wr = np.empty(n_pts)
    cell_imu = np.empty(n_pts, dtype=np.int64)
    cell_wmu = np.empty(n_pts)
    cell_imu1 = np.empty(n_pts, dtype=np.int64)  # the upper row's mu cell (sampling.r_mu_cell)
    cell_wmu1 = np.empty(n_pts)
    mu_ray = np.empty(n_pts)
    t_view = np.empty((n_pts, n_l))
    dens = np.empty((n_pts, 3))
    beta = np.empty((n_pts, n_l))
    # The per-sun loops run over the wavelengths padded with zeros to a multiple of WAVELENGTH_PAD (see there)
    n_lp = -(-n_l // WAVELENGTH_PAD) * WAVELENGTH_PAD
    q = np.zeros((n_pts, n_lp))
    sl = np.zeros((n_s, n_n, n_lp), dtype=np.float32)  # as the tables: half the memory traffic
    sl_flat = sl.reshape(n_s * n_n, n_lp)
    sl_line = sl.reshape(n_s * n_n * n_lp)
    d_rows = density.reshape(n_r * n_mu, n_s * n_n * n_l)  # each (r, mu) texel's (mu_s, nu, wavelength) values
    acc = np.empty((n_s, n_n, n_lp), dtype=np.float32)  # the sums over the ray, float32 (see the loop)
    acc_flat = acc.reshape(n_s * n_n, n_lp)
    q32 = np.zeros((n_pts, n_lp), dtype=np.float32)  # the ray's quadrature weights as the sums take them
    nu_flat = np.empty(n_s * n_n)
    cell = np.empty(n_s * n_n, dtype=np.int64)
    w_s = np.empty(n_s * n_n)
    w_n = np.empty(n_s * n_n)
    steep = np.empty(n_s * n_n, dtype=np.bool_)  # the sun-zenith cell read log-linearly (_sun_cells)
    big_a = mu_s_limit_a(mu_s_min, bottom, top)
    theta_max = acos_table(mu_s_min)
    mu_s_tab = mu_s_texels(bottom, top, mu_s_min, n_s)
    j_log = 0  # the first sun-zenith texel at or above LOG_SUN_ZENITH_BELOW
    while j_log < n_s and mu_s_tab[j_log] < math.sin(LOG_SUN_ZENITH_BELOW):
        j_log += 1
    mu_s_flat = np.repeat(mu_s_tab, n_n)
    for idx in range(start, stop):
        i_r = idx // n_mu
        i_mu = idx % n_mu
        r, mu, hits = scattering_r_mu_params(i_r, i_mu, bottom, top, n_r, n_mu)
        d_end = distance_to_boundary(r, mu, hits, bottom, top)
        if d_end <= 0.0:
            continue
        for i_s in range(n_s):
            for i_n in range(n_n):
                nu_flat[i_s * n_n + i_n] = scattering_nu_param(i_n, mu, mu_s_tab[i_s], n_n)
        for i in range(n_pts):
            d = ray_sample_distance(i, n_samples, d_end, mu, hits)
            dist[i] = d
            r_i, mu_i = point_along_ray(r, mu, d, bottom, top)
            rad[i] = r_i
            mu_ray[i] = mu_i
            a, b, c, e, c1, e1 = r_mu_cell(r_i, mu_i, hits, bottom, top, n_r, n_mu)
            cell_ir[i] = a
            cell_wr[i] = b
            cell_imu[i] = c
            cell_wmu[i] = e
            cell_imu1[i] = c1
            cell_wmu1[i] = e1
            for p in range(3):
                dens[i, p] = density_at(profiles[p], counts[p], r_i - bottom)
            for k in range(n_l):
                beta[i, k] = beta_r[k] * dens[i, 0] + beta_m[k] * dens[i, 1]
        ray_transmittance(dist, dens, extinction, t_view)
        q[:] = 0.0
        for i in range(n_samples):
            for k in range(n_l):
                # scattering coefficient x view transmittance as the exponential factor (see single scattering)
                ca, cb = exp_segment_weights(beta[i, k] * t_view[i, k], beta[i + 1, k] * t_view[i + 1, k],
                                             dist[i + 1] - dist[i])
                q[i, k] += ca * t_view[i, k]
                q[i + 1, k] += cb * t_view[i + 1, k]
        acc[:] = 0.0
        for i in range(n_pts):
            # the scattering coefficient at the sample goes with the weight, not into the slice: the slice's reads
            # (and their log-linear weights, which a factor per wavelength leaves as they are) are the same
            for k in range(n_l):
                q32[i, k] = np.float32(q[i, k] * beta[i, k])
        for i in range(n_pts):
            # The sample's (r, mu) cell is the same for every sun: interpolate the density over it once, into a
            # slice over (mu_s, nu); each lookup is then bilinear (the same value as the quadrilinear one).
            ir, wr, imu, wmu = cell_ir[i], cell_wr[i], cell_imu[i], cell_wmu[i]
            imu1, wmu1 = cell_imu1[i], cell_wmu1[i]  # the upper row at its own mu cell
            c00, c01 = (1.0 - wr) * (1.0 - wmu), (1.0 - wr) * wmu
            c10, c11 = wr * (1.0 - wmu1), wr * wmu1
            # in float32, like the table and the slice: 8 SIMD lanes and no conversions (the slice was a quarter of
            # this kernel's time in float64; the values change by float32 rounding)
            e00, e01, e10, e11 = np.float32(c00), np.float32(c01), np.float32(c10), np.float32(c11)
            d00 = d_rows[ir * n_mu + imu]
            d01 = d_rows[ir * n_mu + imu + 1]
            d10 = d_rows[(ir + 1) * n_mu + imu1]
            d11 = d_rows[(ir + 1) * n_mu + imu1 + 1]
            if n_l == n_lp:
                # the slice's layout is the table's: one loop over all its values (7 % of this kernel's time
                # against a loop per sun, 16 wavelengths, one thread)
                for t in range(n_s * n_n * n_l):
                    sl_line[t] = e00 * d00[t] + e01 * d01[t] + e10 * d10[t] + e11 * d11[t]
            else:
                for j in range(n_s * n_n):
                    for k in range(n_l):
                        t = j * n_l + k
                        sl_flat[j, k] = e00 * d00[t] + e01 * d01[t] + e10 * d10[t] + e11 * d11[t]
            _sun_cells(r, dist[i], rad[i], mu_ray[i], mu_s_flat, nu_flat, bottom, top, mu_s_min, big_a, theta_max,
                       n_s, n_n, j_log, cell, w_s, w_n, steep)
            for u in range(n_s * n_n):
                c = cell[u]  # the flat (mu_s, nu) cell indexes sl_flat: no integer division per sun (7 % of
                if c < 0:    # this kernel's time, single thread)
                    continue
                # float32 like the slice: the weights per wavelength on 8 SIMD lanes
                ws = np.float32(w_s[u])
                wn = np.float32(w_n[u])
                ws0 = np.float32(1.0 - w_s[u])
                wn0 = np.float32(1.0 - w_n[u])
                # Each loop in float32, the sum over the ray included: all of it on SIMD lanes (a float64 sum, in a
                # second loop because mixed with the float32 values it ran on half the lanes and took 1.4x as long,
                # cost 9 % more of this kernel's time, 16 wavelengths one thread; the sum of the ray's 51 samples in
                # float32 moves the stored half-precision tables by one unit in 376 of 3.1 M values). The padding's
                # zeros give 0 (log_lerp_weight of 0 and 0 is finite).
                if steep[u]:
                    for k in range(n_lp):
                        # linear along nu, log-linear along mu_s (.geometry.log_lerp_weight), each wavelength's weight
                        # from its own values: per-wavelength weights keep the tables independent of the chunking
                        a0 = wn0 * sl_flat[c, k] + wn * sl_flat[c + 1, k]
                        a1 = wn0 * sl_flat[c + n_n, k] + wn * sl_flat[c + n_n + 1, k]
                        acc_flat[u, k] += q32[i, k] * (a0 + log_lerp_weight(a0, a1, ws) * (a1 - a0))
                else:
                    for k in range(n_lp):
                        a0 = wn0 * sl_flat[c, k] + wn * sl_flat[c + 1, k]
                        a1 = wn0 * sl_flat[c + n_n, k] + wn * sl_flat[c + n_n + 1, k]
                        acc_flat[u, k] += q32[i, k] * (ws0 * a0 + ws * a1)
        for i_s in range(n_s):
            for i_n in range(n_n):
                for k in range(n_l):
                    out[i_r - first_r, i_mu, i_s, i_n, k] = acc[i_s, i_n, k]


#: Bits of float32's 0.5: added to a value below float16's smallest normal number, it leaves that value's float16
#: subnormal bits (rounded to nearest even) in the low mantissa bits (:func:`half_bits_kernel`).
_HALF_SUBNORMAL_MAGIC = np.float32(0.5)


@kernel
def half_bits_kernel(table, inv_scale, out):
    """``out[k, i, m, s, n]`` (uint16, the bits of float16 values) = ``table[i, m, s, n, k] * inv_scale[i, s, k]``
    rounded to the nearest float16 (ties to even), for a table (n_r, n_mu, n_mu_s, n_nu, n_wavelengths) float32 >= 0
    and powers of two ``inv_scale`` (n_r, n_mu_s, n_wavelengths) that keep every product at most 65504 (float16's
    largest; :func:`.storage.encode_half` scales to 2^13): the same bits as numpy's float32 -> float16 cast of the
    products, by the integer rounding of the IEEE formats (normal: drop 13 mantissa bits with a carry for ties to
    even after re-biasing the exponent by 127 - 15; subnormal: add 0.5, whose exponent aligns the mantissa to
    float16's subnormal step). numpy casts one value at a time (3 ns each): this loop runs on SIMD lanes (0.45 ->
    0.1 s of CPU for a default precomputation's tables, 2026-12-06)."""
    n_r, n_mu, n_s, n_n, n_l = table.shape
    row = np.empty(n_l, dtype=np.float32)
    sub = np.empty(n_l, dtype=np.float32)
    row_bits = row.view(np.uint32)
    sub_bits = sub.view(np.uint32)
    magic_bits = 0x3F000000  # the bits of _HALF_SUBNORMAL_MAGIC
    # one (r, mu) slice at a time through a buffer in the output's order: its rows are then copied whole (writing
    # each value straight to its place in the wavelength-first output took twice as long)
    buf = np.empty((n_l, n_s * n_n), dtype=np.uint16)
    for i in range(n_r):
        for m in range(n_mu):
            for j in range(n_s):
                for n in range(n_n):
                    for k in range(n_l):
                        v = table[i, m, j, n, k] * inv_scale[i, j, k]
                        row[k] = v
                        sub[k] = v + _HALF_SUBNORMAL_MAGIC
                    for k in range(n_l):
                        u = np.int64(row_bits[k])
                        normal = (u - 0x38000000 + 0xFFF + ((u >> 13) & 1)) >> 13
                        subnormal = np.int64(sub_bits[k]) - magic_bits
                        buf[k, j * n_n + n] = normal if u >= 0x38800000 else subnormal
            for k in range(n_l):
                dst = out[k, i, m].reshape(n_s * n_n)
                for q in range(n_s * n_n):
                    dst[q] = buf[k, q]
