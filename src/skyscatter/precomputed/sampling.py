"""Interpolated reads of the precomputed tables (numba scalar functions).

Shared by the precomputation kernels (:mod:`.kernels`) and the rendering kernels (:mod:`.lookup`). Every
function writes its per-wavelength result into a caller-provided ``out`` array so that inner loops do not
allocate.

Reference: [Bruneton2008].
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..atmosphere.phase import (
    AEROSOL_PHASE_FUNCTIONS,
    aerosol_phase_scalar,
    cornette_shanks_scalar,
    rayleigh_phase_scalar,
)
from ..atmosphere.phase_table import phase_table_values
from ..jit import helper
from .geometry import (
    MU_S_SPLIT,
    acos_table,
    azimuth_four_point,
    azimuth_read_weights,
    bilinear_weights,
    clamp,
    irradiance_coord,
    irradiance_log_cell,
    irradiance_log_nodes,
    lerp_index,
    log_lerp_weight,
    log_quadratic_weight,
    point_along_ray,
    refined_mu_s_cell,
    scattering_mu_s_coord,
    scattering_nu_coord,
    scattering_nu_param,
    scattering_r_mu_coord,
    scattering_r_mu_rows,
    shadow_exit_altitude,
    transmittance_coord,
)

if TYPE_CHECKING:
    from .parameters import AtmosphereParameters

PI = math.pi
#: Largest shadow factor of the single scattering read from the Earth's shadow, in the rendering lookups
#: (:func:`shadow_ratios_fast`, :func:`.lookup._inscatter`; the GLSL library's ``SHADOW_RATIO_MAX``) and in the
#: precomputation's second-order scattering density (:func:`shadow_nu_weights`, since table format 21): a texel whose
#: ray leaves the shadow in thinner air than the query's is scaled up by the density ratio, at most this much. A cap
#: of 1 only takes light away, so between two texels whose rays leave the shadow below and above the query's the value
#: falls short: 45 deg from a sun 6 deg below the horizon, 2 and 5 deg up, Rayleigh, 400 and 560 nm, -10 % of the
#: independent integral of ``tests/precomputed_reference.py`` on its own texel values where the uncapped ratio gives
#: -1 to -2 % (aerosol -28 to -40 % against -1 to +4 %). Bounded because the tables' shadow is the sun disc's, soft,
#: and their penumbra times an unbounded ratio was 10^5 to 10^13 times too bright (measured; in the precomputation
#: the whole twilight sky came out outside the target). Against the stored Monte Carlo (docs/accuracy.md, "Low sun"):
#: in the lookups, 2 took the Earth defaults from 11 to 7 of 75 directions outside (the hazy skies unchanged); in the
#: precomputation, where the cap had been 1 until table format 21 (2026-12-06), 2 took the twilight multiple
#: scattering 1.2-2.7 % brighter on average at -5.1 and -6 deg (up to +5.6 %) and the directions outside from 25 to
#: 15 of 315 (4: 15, with more outside at -5.1 deg in optical depth 0.5; unbounded: 209).
SHADOW_RATIO_MAX = 2.0
_LOG_SHADOW_RATIO_MAX = math.log(SHADOW_RATIO_MAX)


#: The phase functions of :mod:`skyscatter.atmosphere.phase` as numba scalars: Rayleigh (Bruneton & Neyret
#: 2008, Eq. 2), Cornette-Shanks (Eq. 4, the default aerosol phase) and the aerosol phase of a given kind.
rayleigh_phase = rayleigh_phase_scalar
mie_phase = cornette_shanks_scalar
aerosol_phase = aerosol_phase_scalar
#: ``mie_kind`` of a tabulated, wavelength-dependent aerosol phase function (after the analytic kinds): the kernels
#: then read it per wavelength with ``phase_table_values`` (:mod:`skyscatter.atmosphere.phase_table`).
TABLE_PHASE = len(AEROSOL_PHASE_FUNCTIONS)

#: Asymmetry parameter of the lobe :func:`multiple_lobe` that the multiple-scattering tables are divided by: the
#: Henyey-Greenstein lobe of about the third scattering order of the default aerosol (Legendre moments of a
#: Henyey-Greenstein phase are ``g^l`` and multiply under the convolution of successive orders, so order ``n`` of a
#: ``g`` = 0.8 lobe is about ``HG(0.8^n)``: 0.64, 0.51, 0.41), and 0.5 was the best of 0.4-0.7 on the tables below.
MULTIPLE_LOBE_G = 0.5
#: The lobe's weight per unit aerosol share of the column's scattering optical depth (:func:`lobe_weight`). Measured
#: on a 15-texel table's azimuth texels (560 nm, ground, view 1-20 deg, sun -1 to +12 deg): every second texel read
#: from its neighbours, median of ``read / texel - 1`` [%] at 12.9 / 38.6 / 64.3 / 90 deg from the sun, linear
#: (the precomputation's sphere integrals) and log-linear (the lookups): optical depth 0.5 without the lobe
#: -6.3 / +9.9 / +6.5 / +3.7 and -9.9 / +2.8 / +3.7 / +3.2, with it (0.4) -3.1 / +1.8 / +2.0 / +2.2 and -3.7 / +0.5 /
#: +1.3 / +2.1; turbidity 3 -6.3 / +14.3 / +6.5 / +3.4 and -12.1 / +5.4 / +4.2 / +3.1 -> -4.8 / +5.4 / +2.8 / +2.3
#: and -6.8 / +3.1 / +2.2 / +2.3. 0.6 follows 560 nm a little closer but over-corrects at 400 nm, where air's share
#: is larger than at 550 nm: against the low-sun Monte Carlo (docs/accuracy.md, "Low sun") the hazy directions
#: towards a sun at +10 and +3 deg came out 4-6 points brighter at 400 nm (0.4: 2-4).
MULTIPLE_LOBE_WEIGHT = 0.4


#: Wavelength [nm] of :func:`lobe_weight`'s optical depths: one for all wavelengths, so that the tables do not
#: depend on which wavelengths are computed together.
LOBE_WAVELENGTH = 550.0


def lobe_weight(atmosphere: AtmosphereParameters) -> float:
    """Weight ``a`` [-] of the lobe :func:`multiple_lobe` by which the multiple-scattering tables are
    divided: :data:`MULTIPLE_LOBE_WEIGHT` times the aerosol's share of the column's scattering optical
    depth at :data:`LOBE_WAVELENGTH` (``tau_M,s / (tau_M,s + tau_R)``: 0.04 for the Earth defaults, 0.63 for
    turbidity 3, 0.81 for an aerosol optical depth of 0.5), the columns integrated by the trapezoidal rule on 2001
    heights. The multiply scattered light's forward lobe is the aerosol's; a Rayleigh sky has none."""
    h = np.linspace(0.0, atmosphere.thickness, 2001)
    ray, aer = atmosphere.scattering_coefficients(h, [LOBE_WAVELENGTH])
    tau_r = float(np.trapezoid(ray[:, 0], h))
    tau_m = float(np.trapezoid(aer[:, 0], h))
    total = tau_r + tau_m
    return MULTIPLE_LOBE_WEIGHT * tau_m / total if total > 0.0 else 0.0


@helper
def multiple_lobe(nu, lobe):
    """The shape ``F(nu) = 1 - a + a HG(nu; g)`` by which the multiple-scattering tables (and the orders'
    scattering densities) are divided as they are stored, so that every read between their view-sun azimuth texels
    interpolates ``S / F`` and multiplies by ``F`` at the read's own ``nu``: ``HG`` the Henyey-Greenstein phase
    ([HenyeyGreenstein1941]) times 4 pi (mean 1 over the sphere), ``g`` :data:`MULTIPLE_LOBE_G`, ``a`` = ``lobe``
    (0 <= a < 1: :func:`lobe_weight`, 0 for a sky without aerosol, where the tables are as before).

    Why: a hazy sky's multiply scattered light has the aerosol's forward lobe along the view-sun azimuth, convex in
    its logarithm 20-100 deg from the sun and concave next to it, which 8 azimuth texels 25.7 deg apart do not
    follow; read log-linearly between texels it came out 6-8 % too bright in the second order at 45-90 deg, and the
    precomputation's own reads between texels carried that into orders 3 and up (docs/accuracy.md, "Low sun").
    The same memory holds the ratio, whose logarithm is nearly linear between texels (the paper divides the single
    scattering by its phase functions for the same reason, [Bruneton2008] Sec. 4, "Angular precision").

    Parameters
    ----------
    nu : float
        Cosine of the view-sun angle [-].
    lobe : float
        Weight ``a`` of the lobe [-].
    """
    g = MULTIPLE_LOBE_G
    d = 1.0 + g * g - 2.0 * g * nu
    return 1.0 - lobe + lobe * (1.0 - g * g) / (d * math.sqrt(d))


def multiple_lobe_array(nu: np.ndarray, lobe: float) -> np.ndarray:
    """:func:`multiple_lobe` of an array of view-sun cosines ``nu`` [-] (``lobe`` [-] the weight), in numpy."""
    g = MULTIPLE_LOBE_G
    d = 1.0 + g * g - 2.0 * g * np.asarray(nu, dtype=float)
    return 1.0 - lobe + lobe * (1.0 - g * g) / (d * np.sqrt(d))


@helper
def aerosol_phase_spectrum(nu, g, mie_kind, phase_mu, phase_values, out):
    """``out[k]`` = the aerosol phase [sr^-1] at ``nu`` per wavelength: the table (``mie_kind ==``
    :data:`TABLE_PHASE`; ``phase_mu`` ascending cosines, ``phase_values`` (n_wl, n)) or the analytic kind."""
    if mie_kind == TABLE_PHASE:
        phase_table_values(phase_mu, phase_values, nu, out)
    else:
        p = aerosol_phase(nu, g, mie_kind)
        for k in range(out.shape[0]):
            out[k] = p


@helper
def bilinear_read(table, p0, p1, out):
    """Bilinear read of a 2D table of spectra (n0, n1, n_wavelengths) at texel coordinates (p0, p1)."""
    n0, n1, n_l = table.shape
    i, w0 = lerp_index(p0, 0, n0 - 1)
    j, w1 = lerp_index(p1, 0, n1 - 1)
    a00, a01, a10, a11 = bilinear_weights(w0, w1)
    # the four corner spectra as contiguous rows: the loop over wavelengths vectorises (40 % quicker)
    t00, t01, t10, t11 = table[i, j], table[i, j + 1], table[i + 1, j], table[i + 1, j + 1]
    for k in range(n_l):
        out[k] = a00 * t00[k] + a01 * t01[k] + a10 * t10[k] + a11 * t11[k]


@helper
def transmittance_to_top(table, r, mu, bottom, top, out):
    """Transmittance from (r, mu) to the top of the atmosphere, ignoring the ground (table lookup)."""
    n_r, n_mu, _ = table.shape
    p_r, p_mu = transmittance_coord(r, mu, bottom, top, n_r, n_mu)
    bilinear_read(table, p_r, p_mu, out)


@helper
def transmittance_segment(table, r, mu, d, hits_ground, bottom, top, out, tmp):
    """Transmittance between the ray origin (r, mu) and the point at distance ``d`` [m] along the ray.

    Uses ``T(x, y) = T(x, v) / T(y, v)`` for rays to the top and the reversed rays for rays that meet the
    ground (Bruneton & Neyret 2008, Sec. 4).
    """
    r_d, mu_d = point_along_ray(r, mu, d, bottom, top)
    if hits_ground:
        transmittance_to_top(table, r_d, -mu_d, bottom, top, out)
        transmittance_to_top(table, r, -mu, bottom, top, tmp)
    else:
        transmittance_to_top(table, r, mu, bottom, top, out)
        transmittance_to_top(table, r_d, mu_d, bottom, top, tmp)
    transmittance_ratio(out, tmp)


@helper
def ray_transmittance(dist, dens, extinction, out):
    """Transmittance from a ray's origin to each of its samples, ``out[i, k] = exp(-tau_i)`` (n_pts, n_wl), from
    the optical depth accumulated along the ray itself (Bruneton & Neyret 2008, Eq. 5, on the ray's own samples).

    ``dist`` (n_pts,) ascending distances [m] of the samples from the origin, ``dens`` (n_pts, n_profiles) the
    relative densities there, ``extinction`` (n_profiles, n_wl) the extinction coefficients at density 1 [m^-1]. Each
    step's integral of a density is exact when it varies exponentially between the samples (the layers of Eqs. 1
    and 3; :func:`exp_segment_weights` with a constant second factor), the trapezoid where a value is zero.

    Used by the ray integrals of the precomputation instead of ``T(x, v) / T(y, v)`` from the table (Sec. 4): for
    rays within a few degrees of the horizon near the ground, that ratio of two bilinear reads of a fast-varying
    table was 13-23 % low at the horizon and up to +12 % high just below it (docs/bruneton.md).
    """
    n_pts, n_p = dens.shape
    n_l = out.shape[1]
    for k in range(n_l):
        out[0, k] = 1.0
    for i in range(n_pts - 1):
        h = dist[i + 1] - dist[i]
        for k in range(n_l):
            out[i + 1, k] = 0.0
        for p in range(n_p):
            a = dens[i, p]
            b = dens[i + 1, p]
            ca, cb = exp_segment_weights(a, b, h)
            seg = ca * a + cb * b
            for k in range(n_l):
                out[i + 1, k] += extinction[p, k] * seg
    # out holds each step's optical depth: accumulate and exponentiate
    for k in range(n_l):
        tau = 0.0
        for i in range(1, n_pts):
            tau += out[i, k]
            out[i, k] = math.exp(-tau)


@helper
def transmittance_ratio(out, tmp):
    """``out /= tmp`` per wavelength, capped at 1 and 0 where ``tmp`` is 0: ``T(x, y) = T(x, v) / T(y, v)``
    (Sec. 4) from two transmittances to the top."""
    for k in range(out.shape[0]):
        out[k] = min(out[k] / tmp[k], 1.0) if tmp[k] > 0.0 else 0.0


@helper
def sun_visible_fraction(r, mu_s, bottom, alpha):
    """Fraction of the solar disc (angular radius ``alpha`` [rad]) above the planet's horizon seen from ``r``.

    The horizon is a straight line across the small disc, so the visible part is a circular segment:
    ``1/2 + (h sqrt(1 - h^2) + asin h) / pi`` with ``h`` the elevation of the disc centre above the horizon in
    disc radii.
    """
    sin_h = bottom / r
    cos_h = -math.sqrt(max(1.0 - sin_h * sin_h, 0.0))
    h = clamp((mu_s - cos_h) / (max(sin_h, 1e-6) * alpha), -1.0, 1.0)
    # 0 and 1 exactly at h = -1 and 1; asin h = pi / 2 - acos h, with the polynomial arc cosine (2.2e-8 rad, so
    # the fraction is within 1e-8) because it vectorises (the single-scattering kernel evaluates it per sun)
    return 0.5 + (h * math.sqrt(1.0 - h * h) + (0.5 * PI - acos_table(h))) / PI


@helper
def transmittance_to_sun(table, r, mu_s, bottom, top, alpha, out):
    """Transmittance to the sun from radius ``r`` (sun zenith cosine ``mu_s``), times the visible disc fraction."""
    f = sun_visible_fraction(r, mu_s, bottom, alpha)
    if f <= 0.0:
        for k in range(out.shape[0]):
            out[k] = 0.0
        return
    transmittance_to_top(table, r, mu_s, bottom, top, out)
    for k in range(out.shape[0]):
        out[k] *= f


@helper
def irradiance_read(table, p_r, p_m, out):
    """Read of an irradiance table (n_r, n_mu_s, n_wavelengths) at index positions (p_r, p_m): linear in r, and
    along the sun zenith linear, or in the cells that start below the horizon (:func:`.geometry.irradiance_log_cell`)
    quadratic in the logarithm over the three nearest texel columns (:func:`.geometry.irradiance_log_nodes`, each
    column interpolated linearly in r): the weight :func:`.geometry.log_quadratic_weight` (three-point Lagrange in
    ``ln E``, [Abramowitz1964] Eq. 25.2.11, kept between the cell's two columns) of the cell's two columns, each
    wavelength its own (the tables then do not depend on how the wavelengths are chunked). One weight for all
    wavelengths, that of the three columns' illuminance (the rendering lookups' read in formats 15-18, dropped with
    realtime manifest version 10), was +10.3 % at 400 nm and -7.2 % at 700 nm with the sun 6 deg below the horizon,
    each wavelength's own -1.4 / -1.2 % (turbidity 3, 16 wavelengths, against the hemisphere integral of
    ``benchmarks/second_order_low_sun.py``; docs/accuracy.md, "Low sun").

    Below the horizon the twilight sky irradiance falls faster the lower the sun: the geometric read of two columns
    (format 14) was 4-11 % low between the default 64 texels at -2 to -5.5 deg (turbidity 3, 560 nm, against a table
    8 times finer and the hemisphere integral of ``benchmarks/second_order_low_sun.py``); docs/accuracy.md, "Low
    sun", gives the figures of this read."""
    n0, n1, n_l = table.shape
    i, w0 = lerp_index(p_r, 0, n0 - 1)
    j, w1 = lerp_index(p_m, 0, n1 - 1)
    if not irradiance_log_cell(j, n1) or n1 < 3:
        bilinear_read(table, p_r, p_m, out)
        return
    v0 = 1.0 - w0
    j0, t = irradiance_log_nodes(p_m, n1)
    c = j0 if t < 0.0 else j0 + 1  # the cell's first column
    t00, t01, t02 = table[i, j0], table[i, j0 + 1], table[i, j0 + 2]
    t10, t11, t12 = table[i + 1, j0], table[i + 1, j0 + 1], table[i + 1, j0 + 2]
    for k in range(n_l):
        e0 = v0 * t00[k] + w0 * t10[k]
        e1 = v0 * t01[k] + w0 * t11[k]
        e2 = v0 * t02[k] + w0 * t12[k]
        a, b = (e0, e1) if c == j0 else (e1, e2)
        out[k] = a + log_quadratic_weight(e0, e1, e2, t) * (b - a)


@helper
def irradiance_lookup(table, r, mu_s, bottom, top, out):
    """Read of an irradiance table (n_r, n_mu_s, n_wavelengths) at radius ``r`` [m] and sun zenith cosine ``mu_s``
    (:func:`irradiance_read`)."""
    n_r, n_m, _ = table.shape
    p_r, p_m = irradiance_coord(r, mu_s, bottom, top, n_r, n_m)
    irradiance_read(table, p_r, p_m, out)


@helper
def r_mu_cell(r, mu, hits_ground, bottom, top, n_r, n_mu):
    """Interpolation cell ``(i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1)`` of a view ray in the 4D tables: the radius
    cell and the ``mu`` cells at which its lower and upper rows are read (:func:`.geometry.scattering_r_mu_rows`:
    each at its own coordinate in the cell touching the ground, the query's elsewhere; mu stays in its half)."""
    p_r, p_mu0, p_mu1 = scattering_r_mu_rows(r, mu, hits_ground, bottom, top, n_r, n_mu)
    i_r, w_r = lerp_index(p_r, 0, n_r - 1)
    half = n_mu // 2
    if hits_ground:
        i_mu0, w_mu0 = lerp_index(p_mu0, 0, half - 1)
        i_mu1, w_mu1 = lerp_index(p_mu1, 0, half - 1)
    else:
        i_mu0, w_mu0 = lerp_index(p_mu0, half, n_mu - 1)
        i_mu1, w_mu1 = lerp_index(p_mu1, half, n_mu - 1)
    return i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1


#: A linear weight within this of 0 or 1 is the texel itself (:func:`snap_to_texel`).
TEXEL_SNAP = 1e-9


@helper
def snap_to_texel(w):
    """The linear weight ``w`` of a cell, 0 or 1 when it is within :data:`TEXEL_SNAP` of either: the scattering
    density is computed at the tables' radii and sun zeniths, whose coordinates come back from the mappings a
    rounding error (up to 1e-11) off the texel; with the weight exact the reads skip the other texel's corners
    (three quarters of them)."""
    if w < TEXEL_SNAP:
        return 0.0
    if w > 1.0 - TEXEL_SNAP:
        return 1.0
    return w


@helper
def mu_s_nu_cell(mu, mu_s, nu, bottom, top, mu_s_min, n_mu_s, n_nu, cells):
    """Interpolation cell (i_mu_s, w_mu_s, i_nu, w_nu) in the 4D tables (view zenith cosine ``mu``) of ``n_mu_s``
    sun-zenith texels, whose first ``cells`` stored cells are split (:func:`.geometry.refined_mu_s_cell`; 0 for the
    tables as stored)."""
    p_s = scattering_mu_s_coord(mu_s, bottom, top, mu_s_min, n_mu_s - (MU_S_SPLIT - 1) * cells)
    p_n = scattering_nu_coord(mu, mu_s, nu, n_nu)
    i_s, w_s = refined_mu_s_cell(p_s, n_mu_s, cells)
    i_n, w_n = lerp_index(p_n, 0, n_nu - 1)
    return i_s, w_s, i_n, w_n


@helper
def r_mu_s_cell(r, mu_s, bottom, top, mu_s_min, n_r, n_mu_s, cells):
    """Interpolation cell (i_r, w_r, i_mu_s, w_mu_s, w_r_ground) of an observer radius and sun zenith cosine in the
    4D tables (the axes that stay fixed for one observer); ``w_r`` is the radius weight of the rays that miss the
    ground, ``w_r_ground`` that of the rays that meet it, in the same cell (:func:`.geometry.scattering_r_mu_coord`);
    ``cells`` as in :func:`mu_s_nu_cell`."""
    p_r, _ = scattering_r_mu_coord(r, 1.0, False, bottom, top, n_r, 4)
    i_r, w_r = lerp_index(p_r, 0, n_r - 1)
    p_g, _ = scattering_r_mu_coord(r, -1.0, True, bottom, top, n_r, 4)
    _, w_g = lerp_index(p_g, 0, n_r - 1)
    i_s, w_s = refined_mu_s_cell(scattering_mu_s_coord(mu_s, bottom, top, mu_s_min,
                                                       n_mu_s - (MU_S_SPLIT - 1) * cells), n_mu_s, cells)
    return i_r, w_r, i_s, w_s, w_g


@helper
def cell_corner(q, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s):
    """Corner ``q`` (0-7: bits r, mu, mu_s) of a 4D table's (r, mu, mu_s) cell (the rows ``i_r``, ``i_r + 1`` at
    their own mu cells, :func:`r_mu_cell`): its indices ``(i_r', i_mu', i_mu_s')`` and its linear weight."""
    a = q >> 2
    b = (q >> 1) & 1
    c = q & 1
    wa = w_r if a else 1.0 - w_r
    w_mu = w_mu1 if a else w_mu0
    return (i_r + a, (i_mu1 if a else i_mu0) + b, i_s + c,
            wa * (w_mu if b else 1.0 - w_mu) * (w_s if c else 1.0 - w_s))


@helper
def _column(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, j, k):
    """A 4D table's azimuth texel ``j`` at wavelength index ``k``, interpolated linearly in r, mu and mu_s (the cell
    of :func:`nu_weight`)."""
    v = 0.0
    for a in range(2):
        wa = w_r if a else 1.0 - w_r
        i_mu = i_mu1 if a else i_mu0
        w_mu = w_mu1 if a else w_mu0
        for b in range(2):
            wb = wa * (w_mu if b else 1.0 - w_mu)
            for c in range(2):
                v += wb * (w_s if c else 1.0 - w_s) * table[i_r + a, i_mu + b, i_s + c, j, k]
    return v


@helper
def nu_weight(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, w_n):
    """The weight of texel ``i_n + 1`` along the azimuth (nu) axis of a cell of a 4D table (..., n_wavelengths):
    :func:`.geometry.log_lerp_weight` of the table's middle wavelength (index ``n_wavelengths // 2``: 560 nm of the
    default 16 and of 400, 560, 700 nm) in the two columns at ``i_n`` and ``i_n + 1``, each interpolated linearly in
    r, mu and mu_s (the rows ``i_r``, ``i_r + 1`` at their mu cells ``i_mu0``, ``i_mu1``: :func:`r_mu_cell`);
    ``w_n`` the linear weight. One wavelength, not all: the weight then reads 16 texel values instead of
    16 per wavelength, and a table's radiance at a wavelength depends on its other wavelengths only through the
    middle one's."""
    s0 = _column(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, table.shape[4] // 2)
    s1 = _column(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n + 1, table.shape[4] // 2)
    return log_lerp_weight(s0, s1, w_n)


@helper
def lookup4_cell(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, w_n, scale, out):
    """``out += scale * table(cell)``: interpolation of a 4D table (..., n_wavelengths), linear in r, mu and mu_s
    (the rows ``i_r``, ``i_r + 1`` at their mu cells ``i_mu0``, ``w_mu0`` and ``i_mu1``, ``w_mu1``: :func:`r_mu_cell`)
    and log-linear along nu (:func:`nu_weight`; ``w_n`` the linear weight)."""
    n_l = table.shape[4]
    w_n = nu_weight(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, w_n)
    for a in range(2):
        wa = w_r if a else 1.0 - w_r
        if wa == 0.0:
            continue
        i_mu = i_mu1 if a else i_mu0
        w_mu = w_mu1 if a else w_mu0
        for b in range(2):
            wb = wa * (w_mu if b else 1.0 - w_mu)
            if wb == 0.0:
                continue
            for c in range(2):
                wc = wb * (w_s if c else 1.0 - w_s)
                if wc == 0.0:
                    continue
                for e in range(2):
                    we = wc * (w_n if e else 1.0 - w_n)
                    if we == 0.0:
                        continue
                    we *= scale
                    for k in range(n_l):
                        out[k] += we * table[i_r + a, i_mu + b, i_s + c, i_n + e, k]


@helper
def lookup4_cell_azimuth(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, w_n, scale, out):
    """``out += scale * table(cell)``: :func:`lookup4_cell` with the read along nu through four azimuth texels
    (:func:`.geometry.azimuth_four_point`, :func:`.geometry.azimuth_read_weights`: the four-point rule where the
    texels' values are smooth, the log-linear read of the cell where they fall steeply), its weights from the
    middle wavelength; the multiple-scattering table's read in every rendering lookup (its ratio to the lobe,
    :func:`multiple_lobe`)."""
    n_l = table.shape[4]
    km = n_l // 2
    j0, j3, l0, l1, l2, l3 = azimuth_four_point(i_n, w_n, table.shape[3])
    v0 = _column(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, j0, km)
    v1 = _column(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, km)
    v2 = _column(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n + 1, km)
    v3 = _column(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, j3, km)
    l0, l1, l2, l3 = azimuth_read_weights(v0, v1, v2, v3, w_n, l0, l1, l2, l3)
    for e in range(4):
        j = j0 if e == 0 else (i_n if e == 1 else (i_n + 1 if e == 2 else j3))
        we = scale * (l0 if e == 0 else (l1 if e == 1 else (l2 if e == 2 else l3)))
        if we == 0.0:
            continue
        for a in range(2):
            wa = w_r if a else 1.0 - w_r
            if wa == 0.0:
                continue
            i_mu = i_mu1 if a else i_mu0
            w_mu = w_mu1 if a else w_mu0
            for b in range(2):
                wb = wa * (w_mu if b else 1.0 - w_mu)
                if wb == 0.0:
                    continue
                for c in range(2):
                    wc = we * wb * (w_s if c else 1.0 - w_s)
                    if wc == 0.0:
                        continue
                    for k in range(n_l):
                        out[k] += wc * table[i_r + a, i_mu + b, i_s + c, j, k]


@helper
def lookup4_cell_azimuth_each(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, w_n, scale, out, columns):
    """``out += scale * table(cell)``: :func:`lookup4_cell_azimuth` with each wavelength's own weights along nu
    (from its own four texel values), so that a table's value at a wavelength does not depend on the others: the
    precomputation's read (:func:`scattering_lookup`), whose tables must not depend on how the wavelengths are
    chunked; the rendering lookups take the middle wavelength's weights for all, which folds into colour.
    ``columns`` (4, n_wavelengths) float64 is scratch: the four azimuth texels' columns, each interpolated linearly
    in r, mu and mu_s as :func:`_column` does (the same sums in the same order), all wavelengths at once; corners
    of zero weight are not read (the scattering density reads at texel radii and suns: 2 of the 8)."""
    j0, j3, l0, l1, l2, l3 = azimuth_four_point(i_n, w_n, table.shape[3])
    n_l = table.shape[4]
    columns[:] = 0.0
    for q in range(8):
        c_r, c_mu, c_s, wc = cell_corner(q, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s)
        if wc == 0.0:
            continue
        row = table[c_r, c_mu, c_s]
        for k in range(n_l):
            columns[0, k] += wc * row[j0, k]
            columns[1, k] += wc * row[i_n, k]
            columns[2, k] += wc * row[i_n + 1, k]
            columns[3, k] += wc * row[j3, k]
    for k in range(n_l):
        v0, v1, v2, v3 = columns[0, k], columns[1, k], columns[2, k], columns[3, k]
        a0, a1, a2, a3 = azimuth_read_weights(v0, v1, v2, v3, w_n, l0, l1, l2, l3)
        out[k] += scale * (a0 * v0 + a1 * v1 + a2 * v2 + a3 * v3)


@helper
def lookup4_cell_spectral(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, w_n, scales, out):
    """``out[k] += scales[k] * table(cell)[k]``: :func:`lookup4_cell` with a scale per wavelength (a tabulated
    aerosol phase)."""
    n_l = table.shape[4]
    w_n = nu_weight(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, w_n)
    for a in range(2):
        wa = w_r if a else 1.0 - w_r
        if wa == 0.0:
            continue
        i_mu = i_mu1 if a else i_mu0
        w_mu = w_mu1 if a else w_mu0
        for b in range(2):
            wb = wa * (w_mu if b else 1.0 - w_mu)
            if wb == 0.0:
                continue
            for c in range(2):
                wc = wb * (w_s if c else 1.0 - w_s)
                if wc == 0.0:
                    continue
                for e in range(2):
                    we = wc * (w_n if e else 1.0 - w_n)
                    if we == 0.0:
                        continue
                    for k in range(n_l):
                        out[k] += we * scales[k] * table[i_r + a, i_mu + b, i_s + c, i_n + e, k]


@helper
def scattering_lookup(table, r, mu, mu_s, nu, hits_ground, bottom, top, mu_s_min, scale, out, columns):
    """``out += scale * S(r, mu, mu_s, nu)`` for a 4D table (n_r, n_mu, n_mu_s, n_nu, n_wavelengths): linear in r,
    mu and mu_s, through four azimuth texels along nu (:func:`lookup4_cell_azimuth_each`, the rule of the rendering
    lookups' read of the multiple scattering with each wavelength's own weights: the four-point rule where the texels
    are smooth, the log-linear read of the cell where they fall steeply).

    The scattering density's integral over the sphere reads the previous order here (the second order's reads the
    single scattering with the shadow-following weights of :func:`scattering_lookup_shadow`). Until table format 19
    it read linearly along nu (the log-linear weight, never above the linear one, had biased the sphere integrals of
    smooth daytime radiance low: optical depth 0.5 over albedo 0.8 against the Monte Carlo, mean -1.15 -> -2.03 %);
    the multiple scattering over its lobe is U-shaped along the azimuth with its bottom between two of the 8 texels,
    which a read through two texels over-reads, order after order. Format 20: the low-sun directions outside the
    target 31 -> 25 of 315 (optical depth 0.5 14 -> 8: the 400 nm cells towards a sun at +3 deg pass), measured
    against the stored Monte Carlo (docs/accuracy.md, "Low sun"). ``columns`` (4, n_wavelengths) float64 is scratch
    (:func:`lookup4_cell_azimuth_each`); weights within :data:`TEXEL_SNAP` of a texel read the texel
    (:func:`snap_to_texel`)."""
    n_r, n_mu, n_s, n_n, n_l = table.shape
    i_r, w_r, i_m0, w_m0, i_m1, w_m1 = r_mu_cell(r, mu, hits_ground, bottom, top, n_r, n_mu)
    i_s, w_s, i_n, w_n = mu_s_nu_cell(mu, mu_s, nu, bottom, top, mu_s_min, n_s, n_n, 0)
    lookup4_cell_azimuth_each(table, i_r, snap_to_texel(w_r), i_m0, w_m0, i_m1, w_m1, i_s, snap_to_texel(w_s), i_n,
                              w_n, scale, out, columns)


@helper
def _lookup4_weighted(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, n0, n1, out):
    """``out += table(cell)``, linear in r, mu and mu_s (each row at its own mu cell, :func:`r_mu_cell`), with the
    weights ``n0``, ``n1`` of the nu texels ``i_n``, ``i_n + 1``."""
    n_l = table.shape[4]
    # every corner read, zero weights too: a test per corner made the rendering lookups' aerial perspective in
    # twilight 8-10 % slower (their weights are never zero), and the precomputation's reads gain little from it
    for a in range(2):
        wa = w_r if a else 1.0 - w_r
        i_mu = i_mu1 if a else i_mu0
        w_mu = w_mu1 if a else w_mu0
        for b in range(2):
            wb = wa * (w_mu if b else 1.0 - w_mu)
            for c in range(2):
                wc = wb * (w_s if c else 1.0 - w_s)
                for e in range(2):
                    we = wc * (n1 if e else n0)
                    for k in range(n_l):
                        out[k] += we * table[i_r + a, i_mu + b, i_s + c, i_n + e, k]


@helper
def shadow_nu_weights(r, mu, mu_s, nu, i_n, w_n, n_nu, bottom, top, profile, n_layers):
    """Weights of the nu texels ``i_n``, ``i_n + 1`` (linear weight ``w_n`` of the second) for a single-scattering
    table of the constituent with density ``profile``, that follow the Earth's shadow: each texel's value is divided
    by the density where the ray of that texel's azimuth (and the query's r, mu, mu_s) leaves the shadow
    (:func:`.geometry.shadow_exit_altitude`), interpolated linearly, and multiplied by that density for the query's
    ray, each ratio at most :data:`SHADOW_RATIO_MAX` (``c``): ``(1 - w) min(f_q / f_0, c) S_0 + w min(f_q / f_1, c)
    S_1``.

    A ray that starts in the shadow scatters sunlight only beyond its exit, and the singly scattered light is
    nearly proportional to the density there: with the sun 6 deg below the horizon, 2 deg above it and 77 / 90 /
    103 deg from the sun (texel / query / texel), the exit is at 26 / 35 / 50 km and the single scattering falls by
    200 times across the cell, and linear interpolation of the texels gives +219 % (Rayleigh, 560 nm, Earth
    defaults) where this gives +10 % (log-linear: -67 %), against the independent integral of
    ``tests/precomputed_reference.py`` (docs/accuracy.md, "Low sun"). Where the ray starts lit (every ray with the
    sun above the horizon seen from below the shadow's edge) all three densities are equal and this is the linear
    interpolation exactly. Used by the second order's scattering density (:func:`scattering_lookup_shadow`) and by
    the rendering lookups for points in the shadow (:func:`.lookup._inscatter`, :func:`lookup4_cell_weighted`)."""
    h_q, h_0, h_1 = shadow_exit_altitudes(r, mu, mu_s, nu, i_n, n_nu, bottom, top)
    a, b = shadow_ratios(h_q, h_0, h_1, profile, n_layers)
    return (1.0 - w_n) * a, w_n * b


@helper
def shadow_exit_altitudes(r, mu, mu_s, nu, i_n, n_nu, bottom, top):
    """Altitudes [m] where the ray of the query (r [m], mu, mu_s, nu) and the rays of the nu texels ``i_n`` and
    ``i_n + 1`` (the query's r, mu and mu_s; ``n_nu`` texels) leave the Earth's shadow
    (:func:`.geometry.shadow_exit_altitude`): ``(h_q, h_0, h_1)``."""
    return (shadow_exit_altitude(r, mu, mu_s, nu, bottom, top),
            shadow_exit_altitude(r, mu, mu_s, scattering_nu_param(i_n, mu, mu_s, n_nu), bottom, top),
            shadow_exit_altitude(r, mu, mu_s, scattering_nu_param(i_n + 1, mu, mu_s, n_nu), bottom, top))


@helper
def shadow_exit_altitudes_cos(r, mu, mu_s, nu, cos_0, cos_1, bottom, top):
    """:func:`shadow_exit_altitudes` with the cosines ``cos_0``, ``cos_1`` of the two texels' azimuths given (a
    table of :func:`.geometry.scattering_nu_azimuth`'s cosines: no libm cosine per ray); the texels' ``nu`` is
    :func:`.geometry.scattering_nu_param`'s ``mu mu_s + sqrt((1 - mu^2)(1 - mu_s^2)) cos(phi)``."""
    s = math.sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0))
    m = mu * mu_s
    return (shadow_exit_altitude(r, mu, mu_s, nu, bottom, top),
            shadow_exit_altitude(r, mu, mu_s, clamp(m + s * cos_0, -1.0, 1.0), bottom, top),
            shadow_exit_altitude(r, mu, mu_s, clamp(m + s * cos_1, -1.0, 1.0), bottom, top))


@helper
def shadow_ratios(h_q, h_0, h_1, profile, n_layers):
    """Shadow factors ``(a, b)`` of the two nu texels of a single-scattering table (:func:`shadow_nu_weights`): the
    density of the constituent (``profile``, ``n_layers`` layers) at the query's shadow exit ``h_q`` [m] over its
    density at each texel's exit ``h_0``, ``h_1`` [m] (:func:`shadow_exit_altitudes`), each at most
    :data:`SHADOW_RATIO_MAX` (the same cap in the precomputation and the rendering lookups)."""
    fq = density_at(profile, n_layers, h_q)
    f0 = density_at(profile, n_layers, h_0)
    f1 = density_at(profile, n_layers, h_1)
    # bounded: the tables' shadow is soft (the sun's disc), the exit altitude a point sun's, and an unbounded ratio
    # would multiply their penumbra
    cap = SHADOW_RATIO_MAX
    a = fq / f0 if f0 * cap > fq else cap
    b = fq / f1 if f1 * cap > fq else cap
    return a, b


@helper
def shadow_ratios_fast(h_q, h_0, h_1, profile, n_layers):
    """:func:`shadow_ratios` for the rendering lookups: for a one-layer profile ``exp_term exp(exp_scale h)``
    (``exp_term > 0``, no linear or constant term: the Rayleigh and aerosol layers of Bruneton & Neyret 2008,
    Eqs. 1 and 3) each ratio is ``exp(exp_scale (h_q - h_i))``, at most :data:`SHADOW_RATIO_MAX`, one ``exp`` per
    texel; otherwise :func:`shadow_ratios` with that cap. The same values to rounding."""
    if n_layers == 1 and profile[0, 1] > 0.0 and profile[0, 3] == 0.0 and profile[0, 4] == 0.0:
        sc = profile[0, 2]
        x0 = sc * (h_q - h_0)
        x1 = sc * (h_q - h_1)
        return math.exp(min(x0, _LOG_SHADOW_RATIO_MAX)), math.exp(min(x1, _LOG_SHADOW_RATIO_MAX))
    return shadow_ratios(h_q, h_0, h_1, profile, n_layers)


@helper
def lookup4_cell_weighted(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, n0, n1, scale, out):
    """``out += scale * table(cell)``, linear in r, mu and mu_s, with the weights ``n0``, ``n1`` of the nu texels
    ``i_n``, ``i_n + 1`` (:func:`shadow_nu_weights` in the rendering lookups for a ray that starts in the Earth's
    shadow)."""
    _lookup4_weighted(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, n0 * scale, n1 * scale, out)


@helper
def lookup4_cell_weighted_spectral(table, i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s, i_n, n0, n1, scales, out):
    """``out[k] += scales[k] * table(cell)[k]``: :func:`lookup4_cell_weighted` with a scale per wavelength (a
    tabulated aerosol phase)."""
    n_l = table.shape[4]
    for a in range(2):
        wa = w_r if a else 1.0 - w_r
        i_mu = i_mu1 if a else i_mu0
        w_mu = w_mu1 if a else w_mu0
        for b in range(2):
            wb = wa * (w_mu if b else 1.0 - w_mu)
            for c in range(2):
                wc = wb * (w_s if c else 1.0 - w_s)
                for e in range(2):
                    we = wc * (n1 if e else n0)
                    for k in range(n_l):
                        out[k] += we * scales[k] * table[i_r + a, i_mu + b, i_s + c, i_n + e, k]


@helper
def scattering_lookup_shadow(table, r, mu, mu_s, nu, hits_ground, bottom, top, mu_s_min, scale, profile, n_layers,
                             out):
    """:func:`scattering_lookup` of a single-scattering table with the azimuth weights of
    :func:`shadow_nu_weights` (the constituent's density ``profile``): the incident single scattering of the
    second order's scattering density at twilight."""
    n_r, n_mu, n_s, n_n, n_l = table.shape
    i_r, w_r, i_m0, w_m0, i_m1, w_m1 = r_mu_cell(r, mu, hits_ground, bottom, top, n_r, n_mu)
    i_s, w_s, i_n, w_n = mu_s_nu_cell(mu, mu_s, nu, bottom, top, mu_s_min, n_s, n_n, 0)
    n0, n1 = shadow_nu_weights(r, mu, mu_s, nu, i_n, w_n, n_n, bottom, top, profile, n_layers)
    _lookup4_weighted(table, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, n0 * scale, n1 * scale, out)


@helper
def density_at(profile, n_layers, h):
    """Relative density of a profile (rows: width, exp_term, exp_scale, linear_term, constant_term) at altitude h."""
    start = 0.0
    for k in range(n_layers):
        if k == n_layers - 1 or h < start + profile[k, 0]:
            v = profile[k, 1] * math.exp(profile[k, 2] * h) + profile[k, 3] * h + profile[k, 4]
            return max(v, 0.0)
        start += profile[k, 0]
    return 0.0


@helper
def exp_segment_weights(sa, sb, h):
    """Weights (c_a, c_b) with ``integral_0^h s(t) g(t) dt ~= c_a s_a g_a + c_b s_b g_b``.

    Product integration: ``s`` varies exponentially between its end values ``s_a``, ``s_b`` (exact for the
    exponential density layers of Eqs. 1 and 3) and ``g`` (transmittance, phase-weighted radiance) linearly.
    With ``x = ln(s_b / s_a)``, ``c_a = h f(x)`` and ``c_b = h f(-x)``, ``f(x) = (e^x - 1 - x) / x^2``; this
    tends to the trapezoidal rule (h/2, h/2) as x -> 0, which is also used when an end value is zero.
    """
    if sa <= 0.0 or sb <= 0.0:
        return 0.5 * h, 0.5 * h
    ratio = sb / sa
    x = math.log(ratio)
    if abs(x) < 1e-3:
        fa = 0.5 + x / 6.0 + x * x / 24.0
        fb = 0.5 - x / 6.0 + x * x / 24.0
    else:
        x2 = x * x
        fa = (ratio - 1.0 - x) / x2
        fb = (1.0 / ratio - 1.0 + x) / x2
    return h * fa, h * fb
