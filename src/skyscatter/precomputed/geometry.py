"""Ray geometry in a spherical atmosphere and the table parameterisations (numba scalar functions).

A view ray starts at radius ``r`` [m] with direction cosine ``mu`` against the local vertical; the sun has
direction cosine ``mu_s`` there and ``nu`` is the cosine of the view-sun angle (Bruneton & Neyret 2008,
Sec. 4, notation of the paper). Rays that meet the planet end on the ground, others at the top of the
atmosphere.

Table coordinates are *index positions* ``p`` in ``[0, n - 1]``: texel ``i`` sits at ``p = i`` and a lookup
interpolates linearly between ``floor(p)`` and ``floor(p) + 1``, so the first and last texels hold the values
at the ends of each range exactly.

Mappings (Sec. 4, "Parameterization", with the distance-based forms of Bruneton's 2017 rewrite):

* ``rho = sqrt(r^2 - R_g^2)`` (distance to the horizon), ``H = sqrt(R_t^2 - R_g^2)``; ``x_r = rho / H``
  (the paper's ``u_r``).
* Transmittance table: ``x_mu = (d - d_min) / (d_max - d_min)`` with ``d`` the distance to the top boundary,
  ``d_min = R_t - r`` (looking up) and ``d_max = rho + H`` (looking at the horizon). Only rays that miss the
  ground are stored; the others use ``T(x, y) = T(y, -v) / T(x, -v)`` (Sec. 4).
* Scattering tables: ``u_mu`` is split at the horizon (the paper's Figure 4), which keeps the discontinuity
  of the ray length out of the interpolation. The first half of the ``mu`` axis holds rays that meet the
  ground, ordered from grazing (index 0) to straight down, with ``x = (d - d_min) / (d_max - d_min)``,
  ``d`` the distance to the ground, ``d_min = r - R_g``, ``d_max = rho``; the second half holds the other rays
  from straight up to grazing, with the mean of ``(d - d_min) / (d_max - d_min)`` (``d`` the distance to the
  top, ``d_min = R_t - r``, ``d_max = rho + H``) and ``theta / theta_h`` (zenith angle over the horizon's).
* ``u_mu_s``: with ``d`` the distance from the ground to the top along the sun direction,
  ``a = (d - d_min) / (d_max - d_min)`` (``d_min = R_t - R_g``, ``d_max = H``) and ``A`` its value at the
  largest tabulated sun zenith, the mean of ``max(1 - a / A, 0) / (1 + a)`` (dense near the horizon like the
  paper's ``(1 - exp(-3 mu_s - 0.6)) / (1 - exp(-3.6))`` but ending exactly at the chosen ``mu_s_min``) and
  ``1 - theta_s / theta_max``.
* ``x_nu = 1 - phi / pi``, ``phi`` the azimuth between view and sun (the paper's ``(1 + nu) / 2`` needs ``nu``
  clamped per texel).
* Irradiance table: ``x_r = (r - R_g) / (R_t - R_g)``, ``x_mu_s = (1 + mu_s) / 2``.

The angular halves of the ``mu`` (sky) and ``mu_s`` mappings and the azimuth ``nu`` axis are skyscatter's
(docs/bruneton.md): the distance mappings alone leave 36-42 deg around the zenith in one cell, across which the
forward-peaked multiple scattering of aerosols was interpolated (+18 % to +44 % against DISORT,
``docs/bruneton.md``). Parameters of texels in the mixed halves are found by bisection in the angle.

Reference: [Bruneton2008].
"""

from __future__ import annotations

import math
from typing import cast

import numpy as np

from ..jit import CONTRACT_ARCP, helper

__all__ = [
    "acos_table",
    "azimuth_four_point",
    "azimuth_lagrange",
    "azimuth_read_weights",
    "bilinear_weights",
    "clamp",
    "distance_to_bottom",
    "distance_to_boundary",
    "distance_to_top",
    "in_earth_shadow",
    "irradiance_coord",
    "irradiance_log_cell",
    "irradiance_log_nodes",
    "irradiance_params",
    "lerp_index",
    "log_cubic_nodes",
    "log_cubic_value",
    "log_lerp_weight",
    "log_quadratic_weight",
    "point_along_ray",
    "ray_hits_ground",
    "refined_mu_s_cell",
    "refined_mu_s_count",
    "scattering_nu_azimuth",
    "scattering_nu_coord",
    "scattering_nu_param",
    "scattering_params",
    "scattering_r_mu_rows",
    "ground_cell_rows_apart",
    "scattering_row_mu_coord",
    "shadow_exit_altitude",
    "transmittance_coord",
    "transmittance_params",
    "twilight_cells",
]


#: Sun zenith cosines this close below the tables' limit ``mu_s_min`` count as at the limit: a sun exactly there
#: (a texel's, or a caller's at ``max_sun_zenith``) must not be kept or dropped by the last bit of rounding.
MU_S_LIMIT_TOLERANCE = 1e-12

#: Coefficients of [Abramowitz1964] Eq. 4.4.46 (from Hastings
#: 1955): ``acos(x) = sqrt(1 - x) (a0 + a1 x + ... + a7 x^7)`` for 0 <= x <= 1, absolute error <= 2e-8 rad as
#: published (2.18e-8 with the printed 10-decimal coefficients, at x = 0; tests/test_precomputed_geometry.py).
_A0, _A1, _A2, _A3 = 1.5707963050, -0.2145988016, 0.0889789874, -0.0501743046
_A4, _A5, _A6, _A7 = 0.0308918810, -0.0170881256, 0.0066700901, -0.0012624911


@helper(fastmath=CONTRACT_ARCP)
def acos_table(x: float) -> float:
    """Arc cosine [rad] of ``x`` in [-1, 1] to 2.2e-8 rad (Abramowitz & Stegun 4.4.46, ``acos(-x) = pi - acos(x)``)
    for the table coordinates.

    libm's ``acos`` is a call the compiler cannot vectorise and it took half of each lookup; a coordinate
    2e-8 rad off moves a lookup by less than 1e-6 of a texel. Out-of-range ``x`` is clamped.
    """
    a = min(abs(x), 1.0)
    p = ((((((_A7 * a + _A6) * a + _A5) * a + _A4) * a + _A3) * a + _A2) * a + _A1) * a + _A0
    v = math.sqrt(1.0 - a) * p
    return v if x >= 0.0 else math.pi - v


@helper(fastmath=CONTRACT_ARCP)
def clamp(x: float, lo: float, hi: float) -> float:
    return min(max(x, lo), hi)


@helper(fastmath=CONTRACT_ARCP)
def distance_to_top(r: float, mu: float, top: float) -> float:
    """Distance [m] from radius ``r`` along direction cosine ``mu`` to the sphere of radius ``top`` (r <= top).

    Solves ``t^2 + 2 r mu t + r^2 - top^2 = 0`` for its non-negative root, written without cancellation.
    """
    disc = max(r * r * (mu * mu - 1.0) + top * top, 0.0)
    s = math.sqrt(disc)
    if mu > 0.0:
        return max((top * top - r * r) / (r * mu + s), 0.0) if r * mu + s > 0.0 else 0.0
    return max(-r * mu + s, 0.0)


@helper(fastmath=CONTRACT_ARCP)
def distance_to_bottom(r: float, mu: float, bottom: float) -> float:
    """Distance [m] from radius ``r`` along ``mu`` to the first hit of the sphere ``bottom`` (r >= bottom).

    Only meaningful when :func:`ray_hits_ground` is true.
    """
    disc = max(r * r * (mu * mu - 1.0) + bottom * bottom, 0.0)
    s = math.sqrt(disc)
    q = -r * mu + s
    if q <= 0.0:
        return 0.0
    return max((r * r - bottom * bottom) / q, 0.0)


@helper(fastmath=CONTRACT_ARCP)
def point_along_ray(r: float, mu: float, d: float, bottom: float, top: float) -> tuple[float, float]:
    """Radius [m] and view zenith cosine at distance ``d`` [m] along the ray from radius ``r`` with cosine ``mu``:
    ``r_d = sqrt(d^2 + 2 r mu d + r^2)`` (clamped to the atmosphere) and ``mu_d = (r mu + d) / r_d`` (Bruneton &
    Neyret 2008, Sec. 4, the point ``x + d v``)."""
    r_d = clamp(math.sqrt(max(d * d + 2.0 * r * mu * d + r * r, 0.0)), bottom, top)
    return r_d, clamp((r * mu + d) / r_d, -1.0, 1.0)


@helper(fastmath=CONTRACT_ARCP)
def ray_hits_ground(r: float, mu: float, bottom: float) -> bool:
    """True if the ray from radius ``r`` with direction cosine ``mu`` meets the planet."""
    return mu < 0.0 and r * r * (mu * mu - 1.0) + bottom * bottom >= 0.0


@helper(fastmath=CONTRACT_ARCP)
def distance_to_boundary(r: float, mu: float, hits_ground: bool, bottom: float, top: float) -> float:
    """Distance [m] to the end of the ray: the ground if ``hits_ground`` else the top of the atmosphere."""
    if hits_ground:
        return distance_to_bottom(r, mu, bottom)
    return distance_to_top(r, mu, top)


@helper(fastmath=CONTRACT_ARCP)
def lerp_index(p: float, lo: int, hi: int) -> tuple[int, float]:
    """Interpolation cell of index position ``p`` within texels ``lo..hi`` (0 <= lo < hi): (i0, weight of i0 + 1).

    ``p`` is clamped to [lo, hi] (a NaN gives lo); branch-free, so loops over rays vectorise.
    """
    pc = min(max(p, float(lo)), float(hi)) if p == p else float(lo)
    i = min(int(pc), hi - 1)  # pc >= 0: truncation is the floor
    return i, pc - i


#: Floor of the smaller end value, as a fraction of the larger, in :func:`log_lerp_weight`: a texel in the Earth's
#: shadow holds zero (or rounding noise), whose ratio to its lit neighbour is not finite; with the floor the weight is
#: that of a fall by this factor across the cell.
LOG_LERP_FLOOR = float(np.float32(1e-3))  # 1e-3 as float32 holds it (1.00000005e-3): one floor in float32 and float64
# float32 constants: they keep float32 arithmetic float32 (log_lerp_weight); typed float for the annotations
_FLOOR32 = cast(float, np.float32(LOG_LERP_FLOOR))
_ONE32 = cast(float, np.float32(1.0))
_HALF32 = cast(float, np.float32(0.5))


@helper(fastmath=CONTRACT_ARCP)
def log_lerp_weight(a: float, b: float, w: float) -> float:
    """Weight ``w'`` of the second of two values ``a``, ``b`` (>= 0) at the fraction ``w`` of the cell, for the
    interpolation ``a + w' (b - a)`` that follows a value varying exponentially (log-linearly) between them:
    ``w' = w / (w + (1 - w) sqrt(b / a))``. It meets the geometric interpolation ``a^(1 - w) b^w`` at both ends and
    at the centre of the cell (``w' = 1 / (1 + sqrt(b / a))`` there), lies within 0.15 % of the value in between for
    ``b / a`` of 2 and within a factor 1.4 of it for 100 (where the linear one is 8 times too high), increases with
    ``w`` from 0 to 1 (so the value stays between ``a`` and ``b``) and is ``w`` for ``a = b``. It costs a square
    root and a division, where the exact ``((b / a)^w - 1) / (b / a - 1)`` costs a power, a libm call that keeps the
    lookup loops off the SIMD lanes (4x slower luminance lookups, measured).

    Used along the view-sun azimuth of the single-scattering tables (except read from a point in the Earth's shadow,
    :func:`.sampling.shadow_nu_weights`) and of the multiple scattering where its texels fall steeply
    (:func:`azimuth_read_weights`) and, in the orders' ray integrals, along the sun
    zenith and azimuth of the scattering density. At low sun the single-scattered radiance falls by orders of magnitude
    across one azimuth cell where the view ray passes into the Earth's shadow, and a linear interpolation of such a
    fall overshoots: +255 % single scattering at 90 deg from a sun 6 deg below the horizon (2 deg view elevation,
    560 nm) against the independent integral of ``tests/precomputed_reference.py``; in the ray integrals of the
    multiple scattering, too bright a density wherever the sun sets for the ray's samples (docs/accuracy.md, "Low
    sun"). In the lookups the weight is computed from one value per texel (the table's middle wavelength,
    :func:`.sampling.nu_weight`) and applied to every wavelength, so the interpolation stays linear in the table
    values for given coordinates: the observer's slices projected to colour give the same values as the
    per-wavelength lookup (:func:`.lookup.observer_slices`). In the orders' ray integrals each wavelength has its
    own weight, so that the tables do not depend on how the wavelengths are chunked. The smaller value counts as at
    least :data:`LOG_LERP_FLOOR` times the larger in the ratio (the weight is applied to the
    values themselves, so the interpolation still meets both ends). Branch-free: loops of weights over contiguous
    values vectorise (not loops that also gather the values: :func:`.lookup.observer_kernel`).
    """
    # As w a' / (w a' + (1 - w) sqrt(a' b')) (a', b' floored): one division, selects instead of max() (loops of
    # weights over contiguous values vectorise), and float32 constants so that float32 arguments keep the arithmetic
    # in float32 (8 SIMD lanes; the ray integral of the orders: kernels.multiple_scattering_kernel).
    m = a if a > b else b
    lo = _FLOOR32 * m
    a2 = a if a > lo else lo
    b2 = b if b > lo else lo
    wa = w * a2
    d = wa + (_ONE32 - w) * math.sqrt(a2 * b2)
    return wa / d if d > 0.0 else w


@helper(fastmath=CONTRACT_ARCP)
def in_earth_shadow(r: float, mu_s: float, bottom: float) -> bool:
    """True if the point at radius ``r`` [m] with sun zenith cosine ``mu_s`` lies in the Earth's geometric shadow
    (the half cylinder of :func:`shadow_exit_altitude`: ``mu_s < 0`` and ``r^2 (1 - mu_s^2) < R_g^2``); where it
    does not, every ray from it starts lit and :func:`shadow_exit_altitude` is the start's altitude."""
    return mu_s < 0.0 and r * r * (1.0 - mu_s * mu_s) - bottom * bottom < 0.0


@helper(fastmath=CONTRACT_ARCP)
def shadow_exit_altitude(r: float, mu: float, mu_s: float, nu: float, bottom: float, top: float) -> float:
    """Altitude [m] at which the ray from radius ``r`` [m] (view zenith cosine ``mu``, sun zenith cosine ``mu_s``,
    view-sun cosine ``nu``) leaves the Earth's geometric shadow; the start's altitude if it is lit there; at most
    ``top - bottom``.

    The shadow is the half cylinder of radius ``R_g`` behind the planet (points ``y`` with ``y . s < 0`` and
    ``|y - (y . s) s| < R_g``, ``s`` the sun direction; no refraction, the shadow of the tables' transmittance to
    the sun). With ``x`` the start, ``|x|`` = ``r``, the ray ``x + t v`` crosses the cylinder where
    ``(1 - nu^2) t^2 + 2 r (mu - mu_s nu) t + r^2 (1 - mu_s^2) - R_g^2 = 0`` (the larger root) and the plane
    ``y . s = 0`` at ``t = -r mu_s / nu`` (if ``nu > 0``); it leaves at the nearer of the two.
    """
    c = r * r * (1.0 - mu_s * mu_s) - bottom * bottom
    if mu_s >= 0.0 or c >= 0.0:
        return clamp(r - bottom, 0.0, top - bottom)
    a = 1.0 - nu * nu
    b = r * (mu - mu_s * nu)
    t = math.inf
    if a > 1e-12:
        t = (-b + math.sqrt(max(b * b - a * c, 0.0))) / a
    if nu > 0.0:
        t = min(t, -r * mu_s / nu)
    if t == math.inf:
        return top - bottom
    return clamp(math.sqrt(max(t * t + 2.0 * r * mu * t + r * r, 0.0)) - bottom, 0.0, top - bottom)


@helper(fastmath=CONTRACT_ARCP)
def bilinear_weights(w0: float, w1: float) -> tuple[float, float, float, float]:
    """Weights of the four corners (00, 01, 10, 11) of a cell for fractional positions ``w0``, ``w1`` along its
    two axes (the weights that :func:`lerp_index` returns)."""
    return (1.0 - w0) * (1.0 - w1), (1.0 - w0) * w1, w0 * (1.0 - w1), w0 * w1


# --------------------------------------------------------------------------------------------- transmittance


@helper(fastmath=CONTRACT_ARCP)
def transmittance_coord(r: float, mu: float, bottom: float, top: float, n_r: int, n_mu: int) -> tuple[float, float]:
    """Index positions (p_r, p_mu) of (r, mu) in the transmittance table (rays reaching the top)."""
    big_h = math.sqrt(top * top - bottom * bottom)
    rho = math.sqrt(max(r * r - bottom * bottom, 0.0))
    d = distance_to_top(r, mu, top)
    d_min = top - r
    d_max = rho + big_h
    x_mu = (d - d_min) / (d_max - d_min) if d_max > d_min else 0.0
    return clamp(rho / big_h, 0.0, 1.0) * (n_r - 1), clamp(x_mu, 0.0, 1.0) * (n_mu - 1)


@helper(fastmath=CONTRACT_ARCP)
def transmittance_params(i_r: int, i_mu: int, bottom: float, top: float, n_r: int, n_mu: int) -> tuple[float, float]:
    """(r, mu) of texel (i_r, i_mu) of the transmittance table; inverse of :func:`transmittance_coord`."""
    big_h = math.sqrt(top * top - bottom * bottom)
    rho = big_h * i_r / (n_r - 1)
    r = math.sqrt(rho * rho + bottom * bottom)
    d_min = top - r
    d_max = rho + big_h
    d = d_min + (d_max - d_min) * i_mu / (n_mu - 1)
    if d <= 0.0:
        return r, 1.0
    mu = (big_h * big_h - rho * rho - d * d) / (2.0 * r * d)
    return r, clamp(mu, -1.0, 1.0)


# --------------------------------------------------------------------------------------------- irradiance


@helper(fastmath=CONTRACT_ARCP)
def irradiance_coord(r: float, mu_s: float, bottom: float, top: float, n_r: int, n_mu_s: int) -> tuple[float, float]:
    """Index positions (p_r, p_mu_s) in the irradiance table."""
    x_r = clamp((r - bottom) / (top - bottom), 0.0, 1.0)
    x_mu_s = clamp(0.5 * (mu_s + 1.0), 0.0, 1.0)
    return x_r * (n_r - 1), x_mu_s * (n_mu_s - 1)


@helper(fastmath=CONTRACT_ARCP)
def irradiance_params(i_r: int, i_mu_s: int, bottom: float, top: float, n_r: int, n_mu_s: int) -> tuple[float, float]:
    """(r, mu_s) of texel (i_r, i_mu_s) of the irradiance table."""
    r = bottom + (top - bottom) * i_r / (n_r - 1)
    mu_s = 2.0 * i_mu_s / (n_mu_s - 1) - 1.0
    return r, clamp(mu_s, -1.0, 1.0)


@helper(fastmath=CONTRACT_ARCP)
def irradiance_log_cell(i_mu_s: int, n_mu_s: int) -> bool:
    """True if the sun-zenith cell from texel ``i_mu_s`` to ``i_mu_s + 1`` of an irradiance table of ``n_mu_s``
    texels starts below the horizon (texel ``i_mu_s`` at ``mu_s < 0``: the cell below the horizon and the one
    across it), where the reads interpolate log-linearly along ``mu_s`` (:func:`log_lerp_weight`).

    There the sky irradiance on the ground falls nearly exponentially as the sun sets (turbidity 3, 560 nm: 10.8x
    between the texels at -4.55 and -6.38 deg of the default 64), and a linear interpolation of such a fall
    overshoots: +160 % at -6 deg against the hemisphere integral of the independent single scattering of
    ``benchmarks/second_order_low_sun.py`` (docs/accuracy.md, "Low sun"). Above the horizon the irradiance grows
    more slowly than exponentially with ``mu_s`` and the linear interpolation stays (daytime unchanged)."""
    return 2 * i_mu_s < n_mu_s - 1


@helper(fastmath=CONTRACT_ARCP)
def irradiance_log_nodes(p_mu_s: float, n_mu_s: int) -> tuple[int, float]:
    """The three consecutive sun-zenith texels ``j0, j0 + 1, j0 + 2`` nearest the index position ``p_mu_s`` of an
    irradiance table of ``n_mu_s`` (>= 3) texels, and the position ``t = p_mu_s - (j0 + 1)`` in [-1, 1] relative to
    the middle one (the read's cell is ``(j0, j0 + 1)`` for ``t < 0``, else ``(j0 + 1, j0 + 2)``): the cell around
    ``p_mu_s`` and the texel next to its nearer end (the cell's other side at the table's first texel), for
    :func:`log_quadratic_weight`. ``p_mu_s`` is clamped to the table."""
    j, w = lerp_index(p_mu_s, 0, n_mu_s - 1)
    j0 = j - 1 if w < 0.5 else j
    j0 = min(max(j0, 0), n_mu_s - 3)
    return j0, (j + w) - (j0 + 1)


@helper(fastmath=CONTRACT_ARCP)
def log_quadratic_weight(y0: float, y1: float, y2: float, t: float) -> float:
    """Weight ``g`` of the upper end of the cell around ``t`` (``(y0, y1)`` for ``t < 0``, else ``(y1, y2)``) for
    the interpolation ``lo + g (hi - lo)`` that follows ``ln y`` quadratic through three values at consecutive
    texels (``t`` in [-1, 1] relative to the middle one, :func:`irradiance_log_nodes`): the three-point Lagrange
    formula ([Abramowitz1964] Eq. 25.2.11) in the logarithm, ``y = y0^(t (t - 1) / 2) y1^(1 - t^2)
    y2^(t (t + 1) / 2)``, kept between the cell's two values (``g`` in [0, 1]); :func:`log_lerp_weight` of the
    cell's two values where one of the three is not positive (a texel in the Earth's shadow or below the tables' sun
    limit, whose logarithm is not finite), the fraction of the cell where its two values are equal.

    The twilight sky irradiance on the ground falls faster the lower the sun (its logarithm is concave in the sun
    elevation), so the geometric interpolation between two texels (:func:`log_lerp_weight`, exact for a straight
    logarithm) lies below it between them: -4 to -11 % at the cell centres from -2 to -5.5 deg of the default 64
    sun-zenith texels against a table 8 times finer (turbidity 3, 560 nm). The quadratic holds the curvature
    (docs/accuracy.md, "Low sun")."""
    if t < 0.0:
        lo, hi, w = y0, y1, t + 1.0
    else:
        lo, hi, w = y1, y2, t
    if y0 > 0.0 and y1 > 0.0 and y2 > 0.0:
        y = math.exp(0.5 * t * (t - 1.0) * math.log(y0) + (1.0 - t * t) * math.log(y1)
                     + 0.5 * t * (t + 1.0) * math.log(y2))
        if hi == lo:
            return w
        return min(max((y - lo) / (hi - lo), 0.0), 1.0)
    return log_lerp_weight(lo, hi, w)


@helper(fastmath=CONTRACT_ARCP)
def log_cubic_nodes(i_s: int, w_s: float, n_s: int) -> tuple[int, float, float, float, float]:
    """The four consecutive texels ``j0 .. j0 + 3`` (``j0 = i_s - 1`` clamped to ``0 .. n_s - 4``) around the cell
    ``i_s``, ``i_s + 1`` of an axis of ``n_s`` (>= 4) texels, and the four-point Lagrange weights ([Abramowitz1964]
    Eq. 25.2.13) at the position ``x = i_s + w_s - j0`` (in [0, 3]) of the read: ``L_m(x) = prod_(q != m)
    (x - q) / (m - q)``, for :func:`log_cubic_value`."""
    j0 = min(max(i_s - 1, 0), n_s - 4)
    x = (i_s - j0) + w_s
    x1 = x - 1.0
    x2 = x - 2.0
    x3 = x - 3.0
    return j0, -x1 * x2 * x3 / 6.0, 0.5 * x * x2 * x3, -0.5 * x * x1 * x3, x * x1 * x2 / 6.0


@helper(fastmath=CONTRACT_ARCP)
def log_cubic_value(a: float, b: float, l0: float, l1: float, l2: float, l3: float, c0: float, c1: float, c2: float,
                    c3: float) -> float:
    """The four-point Lagrange formula in the logarithm ([Abramowitz1964] Eq. 25.2.13 applied to ``ln y``):
    ``exp(c0 l0 + c1 l1 + c2 l2 + c3 l3)`` with ``l0 .. l3`` the logarithms of four positive values at consecutive
    texels and ``c0 .. c3`` the weights of :func:`log_cubic_nodes`, kept between the values ``a``, ``b`` at the
    ends of the read's cell, so that it meets both at the cell's ends and never leaves them.

    The values of the rendering lookups' sub-texels of the multiple scattering along the sun zenith in the cells
    below and across the horizon (:func:`refined_mu_s_cell`, :func:`.lookup.refine_sun_zenith`; the single
    scattering's are computed): there the sky falls by 2-5 times across one cell of the default 32 texels and the
    slope of its logarithm turns (docs/accuracy.md, "Low sun")."""
    y = math.exp(c0 * l0 + c1 * l1 + c2 * l2 + c3 * l3)
    if a < b:
        return min(max(y, a), b)
    return min(max(y, b), a)


#: The four-point read along the view-sun azimuth (:func:`azimuth_read_weights`) is used where the four texels'
#: values lie within a factor ``AZIMUTH_RATIO_FOUR_POINT`` of each other, the log-linear one of the cell
#: (:func:`log_lerp_weight`) beyond ``AZIMUTH_RATIO_LOG_LINEAR``, and a linear blend of the two in between (so that
#: the read stays continuous). Across falls of 10x from one texel to the next the four-point rule undershoots (100,
#: 10, 1, 0.1 give -0.07 half way between 10 and 1, where the geometric value is 3.2): that is the Earth's shadow's
#: fall in twilight, which the log-linear weight follows. Measured against the stored low-sun Monte Carlo
#: (docs/accuracy.md, "Low sun"): bounds (2, 4), (4, 16) and the four-point rule everywhere gave the same count of
#: directions outside (27 of 315, the reference before the -6 deg cases were remade); (2, 4) keeps the rule to
#: where it holds.
AZIMUTH_RATIO_FOUR_POINT = 2.0
AZIMUTH_RATIO_LOG_LINEAR = 4.0
# float32 copies (exact): float32 arguments keep azimuth_read_weights in float32
_RATIO_FOUR_POINT32 = cast(float, np.float32(AZIMUTH_RATIO_FOUR_POINT))
_RATIO_LOG_LINEAR32 = cast(float, np.float32(AZIMUTH_RATIO_LOG_LINEAR))


@helper(fastmath=CONTRACT_ARCP)
def azimuth_lagrange(t: float) -> tuple[float, float, float, float]:
    """The four-point Lagrange weights ([Abramowitz1964] Eq. 25.2.13) at the fraction ``t`` of the cell between the
    middle two of four texels at -1, 0, 1, 2: ``-t (t - 1) (t - 2) / 6``, ``(t + 1) (t - 1) (t - 2) / 2``,
    ``-(t + 1) t (t - 2) / 2``, ``(t + 1) t (t - 1) / 6``, in the type of ``t`` (float32 for a float32 ``t``)."""
    half = t - t + _HALF32  # the constants in t's type (0.5 exact in both): float32 stays float32 (SIMD lanes)
    one = half + half
    two = one + one
    sixth = half / (one + two)
    return (-t * (t - one) * (t - two) * sixth, half * (t + one) * (t - one) * (t - two),
            -half * (t + one) * t * (t - two), (t + one) * t * (t - one) * sixth)


@helper(fastmath=CONTRACT_ARCP)
def azimuth_four_point(i_n: int, w_n: float, n_nu: int) -> tuple[int, int, float, float, float, float]:
    """The outer texels ``j0``, ``j3`` of the four around the azimuth cell ``i_n``, ``i_n + 1`` of an axis of
    ``n_nu`` (>= 2) texels (the inner ones are ``i_n`` and ``i_n + 1``) and the four-point weights
    (:func:`azimuth_lagrange`) of the four at the fraction ``w_n`` of the cell. The axis is the view-sun azimuth
    from 0 to pi (:func:`scattering_nu_azimuth`), and the sky is symmetric about both ends (the azimuths ``-phi`` and
    ``phi`` are the same view-sun angle, as are ``pi + phi`` and ``pi - phi``), so the texel before the first is the
    second and the one after the last the one before it. The read is exact for a cubic in the texel index in the
    interior cells, and in the two end cells for a quadratic even about the nearer end (the sky's slope along the
    azimuth is zero at both ends; the read's slope there is not exactly zero, so it has a small kink at 0 and pi)."""
    j0 = i_n - 1 if i_n > 0 else 1
    j3 = i_n + 2 if i_n + 2 <= n_nu - 1 else 2 * (n_nu - 1) - (i_n + 2)
    l0, l1, l2, l3 = azimuth_lagrange(w_n)
    return j0, j3, l0, l1, l2, l3


@helper(fastmath=CONTRACT_ARCP)
def azimuth_read_weights(s0: float, s1: float, s2: float, s3: float, w_n: float, l0: float, l1: float, l2: float,
                         l3: float) -> tuple[float, float, float, float]:
    """Weights of the four texels of :func:`azimuth_four_point` for the rendering lookups' read of the multiple
    scattering along the view-sun azimuth, from the four texels' values ``s0 .. s3`` (>= 0; the table's middle
    wavelength, so that one set of weights serves every wavelength and the read folds into colour): the
    four-point weights ``l0 .. l3`` where the values lie within a factor :data:`AZIMUTH_RATIO_FOUR_POINT` of each
    other, the log-linear read of the cell (``0, 1 - g, g, 0``, ``g`` :func:`log_lerp_weight` of ``s1``, ``s2`` at
    ``w_n``) beyond :data:`AZIMUTH_RATIO_LOG_LINEAR` (or where a value is not positive), blended linearly in the
    ratio in between. The weights sum to 1 and give ``s1`` at ``w_n = 0``, ``s2`` at ``w_n = 1``. Branch-free, and
    float32 throughout for float32 arguments (the observer's loop over rays runs on SIMD lanes).

    Why: the multiple scattering over its lobe (:func:`.sampling.multiple_lobe`) is U-shaped along the azimuth,
    lowest between two of the 8 texels (25.7 deg apart) 70-110 deg from the sun, where a read through two texels
    is a few per cent high: +3 % at 90 deg from a sun 3 deg up, optical depth 0.5 (the tables of 16 texels hold
    0.840, 0.832, 0.844 around it, the two-texel read 0.861). Measured against the stored low-sun Monte Carlo:
    40 -> 27 of 315 directions outside, 42 -> 31 against the reference whose -6 deg cases have 8x the paths
    (docs/accuracy.md, "Low sun")."""
    zero = w_n - w_n
    one = zero + _ONE32
    lo = min(min(s0, s1), min(s2, s3))
    hi = max(max(s0, s1), max(s2, s3))
    # hi <= R lo <=> the ratio within R; written without a division by lo (which may be zero)
    r4 = zero + _RATIO_FOUR_POINT32
    rl = zero + _RATIO_LOG_LINEAR32
    num = rl * lo - hi  # (R_log - ratio) lo
    den = (rl - r4) * lo
    beta = min(max(num / den, zero), one) if den > zero else zero
    g = log_lerp_weight(s1, s2, w_n)
    return (beta * l0, beta * l1 + (one - beta) * (one - g), beta * l2 + (one - beta) * g, beta * l3)


# --------------------------------------------------------------------------------------------- scattering


@helper(fastmath=CONTRACT_ARCP)
def _mu_s_a(mu_s: float, bottom: float, top: float) -> float:
    big_h = math.sqrt(top * top - bottom * bottom)
    d = distance_to_top(bottom, mu_s, top)
    d_min = top - bottom
    return (d - d_min) / (big_h - d_min)


@helper(fastmath=CONTRACT_ARCP)
def horizon_constants(r: float, bottom: float, top: float) -> tuple[float, float, float]:
    """``(rho, H, theta_h)`` at radius ``r``: distance to the horizon, ``sqrt(R_t^2 - R_g^2)`` and the zenith
    angle of the horizon [rad] (the constants of the ``mu`` mapping for one radius)."""
    big_h = math.sqrt(top * top - bottom * bottom)
    rho = math.sqrt(max(r * r - bottom * bottom, 0.0))
    return rho, big_h, acos_table(-rho / r)


@helper(fastmath=CONTRACT_ARCP)
def sky_mu_unit(r: float, mu: float, top: float, rho: float, big_h: float, theta_h: float) -> float:
    """Unit coordinate of a ray that misses the ground (constants of :func:`horizon_constants`): the mean of the
    2017 distance mapping ``(d - d_min) / (d_max - d_min)`` (dense at the horizon) and the zenith angle over the
    horizon's zenith angle (uniform in angle, so the zenith region is not one cell wide)."""
    # The distance to the top as sqrt(...) - r mu: one division less than distance_to_top's cancellation-free
    # form (this runs for every lookup). Its cancellation towards the zenith costs log10(r / d) digits: 3 at the
    # ground (d >= R_t - R_g = 60 km), 10 one metre below the top.
    d = max(math.sqrt(max(r * r * (mu * mu - 1.0) + top * top, 0.0)) - r * mu, 0.0)
    d_min = top - r
    d_max = rho + big_h
    x_d = (d - d_min) / (d_max - d_min) if d_max > d_min else 0.0
    x_a = acos_table(mu) / theta_h
    return 0.5 * (clamp(x_d, 0.0, 1.0) + clamp(x_a, 0.0, 1.0))


@helper(fastmath=CONTRACT_ARCP)
def ground_mu_unit(r: float, mu: float, bottom: float, rho: float) -> float:
    """Unit coordinate of a ray that meets the ground: 1 - (d - d_min) / (d_max - d_min), ``d`` the distance to
    the ground, ``d_min = r - R_g``, ``d_max = rho`` (0 grazing, 1 straight down)."""
    d = distance_to_bottom(r, mu, bottom)
    d_min = r - bottom
    x = (d - d_min) / (rho - d_min) if rho > d_min else 0.0
    return 1.0 - clamp(x, 0.0, 1.0)


@helper(fastmath=CONTRACT_ARCP)
def _sky_mu_x(r: float, mu: float, bottom: float, top: float) -> float:
    rho, big_h, theta_h = horizon_constants(r, bottom, top)
    return sky_mu_unit(r, mu, top, rho, big_h, theta_h)


#: Altitude [m] below which a cell of rows of the 4D scattering tables starts if the radius weight within it is
#: linear in the altitude (:func:`scattering_r_index`): the cell touching the ground and the one from 62.7 m of the
#: default 32 rows.
ALTITUDE_LINEAR_BELOW = 200.0
#: Altitude [m] that the upper row of such a cell must lie below as well: a cell thicker than that (the first cell
#: of tables with few rows: 0-1230 m with 8 rows) keeps the ``rho`` weight and one shared ``mu`` coordinate, as the
#: radiance's curvature in the altitude over a cell comparable to the aerosol's scale height (1.2 km) outweighs
#: (8-row tables, AOD 0.5, g 0.8, albedo 1, sun 30 deg, 550 nm: the tables' diffuse horizontal irradiance against
#: DISORT +0.85 % with the ``rho`` weight, +4.6 % with the altitude weight and rows apart; 32 rows: -0.46 % either way).
ALTITUDE_LINEAR_CELL_TOP = 300.0


@helper(fastmath=CONTRACT_ARCP)
def ground_cell_rows_apart(bottom: float, top: float, n_r: int) -> bool:
    """True if the cell of the ``n_r`` rows touching the ground (radii ``bottom`` to the first row above it [m]) is
    thin enough (first row below :data:`ALTITUDE_LINEAR_CELL_TOP`) for its rows to be read each at its own ``mu``
    coordinate and weighted linearly in the altitude (:func:`scattering_r_mu_rows`)."""
    if n_r < 2:
        return False
    rho1 = math.sqrt(top * top - bottom * bottom) / (n_r - 1)
    r1 = math.sqrt(rho1 * rho1 + bottom * bottom)
    return rho1 * rho1 < ALTITUDE_LINEAR_CELL_TOP * (r1 + bottom)


@helper(fastmath=CONTRACT_ARCP)
def scattering_r_index(r: float, rho: float, bottom: float, big_h: float, n_r: int) -> float:
    """Index position of radius ``r`` [m] (``rho = sqrt(r^2 - R_g^2)`` [m], ``big_h = sqrt(R_t^2 - R_g^2)`` [m])
    on the ``n_r`` rows of the 4D scattering tables: the rows sit at ``rho_i = H i / (n_r - 1)`` (``x_r = rho / H``,
    Bruneton & Neyret 2008, Sec. 4). Within the cells whose lower row is below :data:`ALTITUDE_LINEAR_BELOW` and
    upper row below :data:`ALTITUDE_LINEAR_CELL_TOP` (the first two cells of the default 32 rows, 0-62.7 m and
    62.7-251 m; the first of 16 rows, 0-268 m; none of 8 rows) the position is linear in ``r`` (the
    altitude), ``i + (r - r_i) / (r_(i+1) - r_i)``; elsewhere linear in ``rho``.

    The radiance is smooth in the altitude, and the altitude a quadratic function of ``rho`` (``h ~ rho^2 / (2
    R_g)``): interpolated linearly in ``rho`` a lookup adds ``~(h_1 / 4) dS/dh`` at the middle of a cell (``h_1`` =
    62.7 m, the first row above the ground; at 10 m the upper row weighs 0.399 in ``rho``, 0.159 in the altitude).
    In the cell touching the ground the rows are read each at its own ``mu`` coordinate
    (:func:`scattering_r_mu_rows`): the coordinate scales with the horizon's zenith angle (90 deg at the ground,
    90.25 deg at 62.7 m), and read at one shared coordinate the two rows are two directions, whose difference the
    ``rho`` weight had partly offset (the altitude weight at the shared coordinate: the default air with the sun at
    75 deg, 2 deg up from 10 m, 0.86 -> 1.43 %). In the second cell the shared coordinate stays (measured better
    there for every air and sun tried: worst error at 150 m 0.62-2.04 % -> 0.27-0.94 %); higher up the cells are
    thicker and the radiance's convexity in the altitude outweighs (the continental aerosol at 2 km, sun at 30 deg:
    0.58 -> 1.27 %; benchmarks/r_interpolation_near_ground.py, docs/aerosols.md). ``r - r_i`` is formed as
    ``(rho^2 - rho_i^2) / (r + r_i)``, without cancellation. Texel rows map to their integer positions exactly."""
    x = clamp(rho / big_h, 0.0, 1.0) * (n_r - 1)
    i = min(int(x), n_r - 2)
    rho0 = big_h * i / (n_r - 1)
    rho1 = big_h * (i + 1) / (n_r - 1)
    r0 = math.sqrt(rho0 * rho0 + bottom * bottom)
    if rho0 * rho0 >= ALTITUDE_LINEAR_BELOW * (r0 + bottom):
        return x
    r1 = math.sqrt(rho1 * rho1 + bottom * bottom)
    if rho1 * rho1 >= ALTITUDE_LINEAR_CELL_TOP * (r1 + bottom):
        return x  # a thick cell (few rows): linear in rho
    rr = max(r, bottom)
    w = (rho * rho - rho0 * rho0) * (r1 + r0) / ((rho1 * rho1 - rho0 * rho0) * (rr + r0))
    return i + clamp(w, 0.0, 1.0)


@helper(fastmath=CONTRACT_ARCP)
def scattering_row_mu_coord(i_r: int, mu: float, bottom: float, top: float, n_r: int, n_mu: int) -> float:
    """Index position on the ``mu`` axis of row ``i_r`` of the 4D scattering tables of a ray with zenith cosine
    ``mu`` that misses the ground: the sky half's mapping (:func:`sky_mu_unit`) with the row's own radius
    ``r_i = sqrt(rho_i^2 + R_g^2)``, ``rho_i = H i_r / (n_r - 1)`` (a direction below that row's horizon maps to
    its horizon)."""
    big_h = math.sqrt(top * top - bottom * bottom)
    rho = big_h * i_r / (n_r - 1)
    r = math.sqrt(rho * rho + bottom * bottom)
    half = n_mu // 2
    return half + sky_mu_unit(r, mu, top, rho, big_h, acos_table(-rho / r)) * (half - 1)


@helper(fastmath=CONTRACT_ARCP)
def scattering_r_mu_coord(r: float, mu: float, hits_ground: bool, bottom: float, top: float,
                          n_r: int, n_mu: int) -> tuple[float, float]:
    """Index positions (p_r, p_mu) of a view ray in the 4D scattering tables.

    ``p_r``: for rays that miss the ground :func:`scattering_r_index` (linear in the altitude within the cells
    below :data:`ALTITUDE_LINEAR_BELOW`); for rays that meet it ``rho / H (n_r - 1)`` (linear in ``rho``): the
    lookup holds the ``mu`` coordinate fixed across the two rows, and in the ground half that coordinate fixes the
    ray's length to the ground as
    ``d_min + x (rho - d_min)``, nearly linear in ``rho``, which the optically thin inscatter follows (the weight
    linear in the altitude took the single scattering 3 deg down from 10 m from +13 % to -55 % against the
    independent integral; benchmarks/r_interpolation_near_ground.py). ``p_mu``: the query's own position; the
    lookups read the rows of the cell touching the ground at positions of their own (:func:`scattering_r_mu_rows`)."""
    rho, big_h, theta_h = horizon_constants(r, bottom, top)
    half = n_mu // 2
    if hits_ground:
        p_r = clamp(rho / big_h, 0.0, 1.0) * (n_r - 1)
        p_mu = ground_mu_unit(r, mu, bottom, rho) * (half - 1)
    else:
        p_r = scattering_r_index(r, rho, bottom, big_h, n_r)
        p_mu = half + sky_mu_unit(r, mu, top, rho, big_h, theta_h) * (half - 1)
    return p_r, p_mu


@helper(fastmath=CONTRACT_ARCP)
def scattering_r_mu_rows(r: float, mu: float, hits_ground: bool, bottom: float, top: float,
                         n_r: int, n_mu: int) -> tuple[float, float, float]:
    """Index positions ``(p_r, p_mu0, p_mu1)`` of a view ray in the 4D scattering tables: ``p_r`` that of
    :func:`scattering_r_mu_coord`, ``p_mu0`` and ``p_mu1`` the ``mu`` positions at which the lower and the upper
    row of its radius cell are read.

    For a ray that misses the ground from within the cell touching the ground (below the first row above it,
    62.7 m of the default 32 rows) each row is read at its own coordinate (:func:`scattering_row_mu_coord`): the
    query's direction, not the query's coordinate, and the two reads combined linearly in the altitude
    (:func:`scattering_r_index`). Measured against the independent single-scattering integral: 5 deg up from 10 m,
    the continental aerosol at 450 nm, the rows at 0 and 62.7 m read in the query's direction are within +0.15 and
    +0.16 %, and combined with the altitude weight 0.159 within +0.15 % where the shared coordinate with the ``rho``
    weight 0.399 gave +0.86 % (benchmarks/r_interpolation_root_cause.py). Elsewhere both are the query's own
    ``mu`` position (Bruneton & Neyret 2008, Sec. 4: one coordinate across the rows, as the GPU's trilinear read
    holds it)."""
    p_r, p_mu = scattering_r_mu_coord(r, mu, hits_ground, bottom, top, n_r, n_mu)
    if hits_ground or p_r >= 1.0 or not ground_cell_rows_apart(bottom, top, n_r):
        return p_r, p_mu, p_mu
    return (p_r, scattering_row_mu_coord(0, mu, bottom, top, n_r, n_mu),
            scattering_row_mu_coord(1, mu, bottom, top, n_r, n_mu))


@helper(fastmath=CONTRACT_ARCP)
def mu_s_limit_a(mu_s_min: float, bottom: float, top: float) -> float:
    """The constant ``A`` of the ``mu_s`` mapping (``a`` at the largest tabulated sun zenith)."""
    return _mu_s_a(mu_s_min, bottom, top)


@helper(fastmath=CONTRACT_ARCP)
def scattering_mu_s_coord_a(mu_s: float, bottom: float, top: float, big_a: float, theta_max: float,
                            n_mu_s: int) -> float:
    """:func:`scattering_mu_s_coord` with ``A = mu_s_limit_a(mu_s_min)`` and ``theta_max = acos(mu_s_min)``
    precomputed (inner loops)."""
    h2 = top * top - bottom * bottom
    disc = max(bottom * bottom * (mu_s * mu_s - 1.0) + top * top, 0.0)
    s = math.sqrt(disc)
    if mu_s > 0.0:
        d = h2 / (bottom * mu_s + s)
    else:
        d = -bottom * mu_s + s
    d_min = top - bottom
    a = (d - d_min) / (math.sqrt(h2) - d_min)
    x_d = clamp(max(1.0 - a / big_a, 0.0) / (1.0 + a), 0.0, 1.0)
    x_a = clamp(1.0 - acos_table(mu_s) / theta_max, 0.0, 1.0)
    return 0.5 * (x_d + x_a) * (n_mu_s - 1)


@helper(fastmath=CONTRACT_ARCP)
def scattering_mu_s_coord(mu_s: float, bottom: float, top: float, mu_s_min: float, n_mu_s: int) -> float:
    """Index position of ``mu_s`` in the scattering tables (0 at ``mu_s_min``, n - 1 at the zenith).

    The mean of the 2017 mapping ``max(1 - a / A, 0) / (1 + a)`` (dense near the horizon, for twilight) and
    ``1 - theta_s / theta_max`` (uniform in the sun's zenith angle): the 2017 mapping alone leaves sun zenith
    angles 0-42 deg in one cell of a 32-texel axis, across which the forward-peaked multiple scattering of
    aerosols cannot be interpolated (+18 % at the zenith against DISORT, docs/bruneton.md).
    """
    return scattering_mu_s_coord_a(mu_s, bottom, top, _mu_s_a(mu_s_min, bottom, top), acos_table(mu_s_min),
                                   n_mu_s)


#: Sub-cells into which the rendering lookups split each sun-zenith cell of the 4D tables below and across the
#: horizon (:func:`twilight_cells`): the lookups read tables refined along the sun zenith
#: (:func:`.lookup.refine_sun_zenith`), whose sub-texels hold the single scattering computed at their suns and
#: :func:`log_cubic_value` of the stored texels for the multiple scattering, linearly between them
#: (docs/accuracy.md, "Low sun").
MU_S_SPLIT = 3


def twilight_cells(bottom: float, top: float, mu_s_min: float, n_mu_s: int) -> int:
    """Number of sun-zenith cells of a 4D table of ``n_mu_s`` texels that the rendering lookups split into
    :data:`MU_S_SPLIT` sub-cells (:func:`.lookup.refine_sun_zenith`): those wholly below the horizon (both texels
    at ``mu_s < 0``) and the one across it, 8 of the default 32 (-12 to +0.78 deg); 0 where fewer than two
    texels lie below the horizon. In the cell across the horizon the sun sets for the ground's own point, a kink in
    the single scattering's columns near the ground that no rule through the texels follows (the four-point rule
    -52 to +18 %, the linear read +8 to +18 %, against tables of three times the texels opposite a sun on the
    horizon, clear air, views 0.2-2 deg; computed: within 2.5 %); the lookups compute the single scattering's
    sub-texels instead (:func:`.compute.stored_single_scattering`) and take the four-point rule for the multiple
    scattering's, which is smooth there. Split so, the sun on the horizon went from 12 to 3 of 45 directions outside
    5 % of the Monte Carlo (docs/accuracy.md, "Low sun"; until 2026-12-05 the cell was read linearly: up to +19.5 %
    at 2 deg elevation towards the sun, turbidity 3).
    ``bottom``, ``top``: the planet's and the atmosphere's radii [m]; ``mu_s_min``: the tables' smallest sun zenith
    cosine."""
    p0 = scattering_mu_s_coord(0.0, bottom, top, mu_s_min, n_mu_s)
    below = min(int(math.ceil(p0)), n_mu_s - 1)  # texels at mu_s < 0 (at least one texel above)
    return below if below >= 2 else 0


def refined_mu_s_count(n_mu_s: int, cells: int) -> int:
    """Texels along the sun zenith of a table of ``n_mu_s`` texels with its first ``cells`` cells split into
    :data:`MU_S_SPLIT` sub-cells each."""
    return n_mu_s + (MU_S_SPLIT - 1) * cells


@helper(fastmath=CONTRACT_ARCP)
def refined_mu_s_cell(p: float, n_fine: int, cells: int) -> tuple[int, float]:
    """Interpolation cell (texel, weight of the next) in a sun-zenith axis of ``n_fine`` texels refined from
    ``n_fine - (MU_S_SPLIT - 1) cells`` stored ones (:func:`refined_mu_s_count`) of the stored index position
    ``p`` (:func:`scattering_mu_s_coord` at the stored count): in the first ``cells`` cells ``MU_S_SPLIT p``, above
    them ``p + (MU_S_SPLIT - 1) cells``, so that every stored texel keeps its value and a read above the split
    cells is the stored axis' own (the same texels and weight: daytime lookups unchanged to the bit). With
    ``cells`` 0 it is :func:`lerp_index` on the stored axis."""
    if p < cells:
        return lerp_index(MU_S_SPLIT * p, 0, n_fine - 1)
    i, w = lerp_index(p, 0, n_fine - 1 - (MU_S_SPLIT - 1) * cells)
    return i + (MU_S_SPLIT - 1) * cells, w


@helper(fastmath=CONTRACT_ARCP)
def scattering_nu_coord(mu: float, mu_s: float, nu: float, n_nu: int) -> float:
    """Index position of ``nu`` in the scattering tables: ``x_nu = 1 - phi / pi`` with ``phi`` the azimuth
    between the view and the sun, ``cos phi = (nu - mu mu_s) / sqrt((1 - mu^2)(1 - mu_s^2))``.

    Every texel is then a direction that exists (the paper's ``(1 + nu) / 2`` clamps ``nu`` into the range its
    ``mu`` and ``mu_s`` allow, so neighbouring texels hold values at other ``nu`` than their coordinates say,
    which smears the forward peak of the multiply scattered light across the table).
    """
    s = math.sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0))
    if s < 1e-9:
        return 0.5 * (n_nu - 1)
    cphi = clamp((nu - mu * mu_s) / s, -1.0, 1.0)
    return (1.0 - acos_table(cphi) / math.pi) * (n_nu - 1)


@helper(fastmath=CONTRACT_ARCP)
def scattering_nu_azimuth(i_nu: int, n_nu: int) -> float:
    """Azimuth ``phi`` [rad] between view and sun of texel index ``i_nu`` (``x_nu = 1 - phi / pi``)."""
    return math.pi * (1.0 - i_nu / (n_nu - 1))


@helper(fastmath=CONTRACT_ARCP)
def scattering_nu_param(i_nu: int, mu: float, mu_s: float, n_nu: int) -> float:
    """``nu`` of texel index ``i_nu`` for view and sun zenith cosines ``mu``, ``mu_s``; inverse of
    :func:`scattering_nu_coord`."""
    s = math.sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0))
    return clamp(mu * mu_s + s * math.cos(scattering_nu_azimuth(i_nu, n_nu)), -1.0, 1.0)


@helper(fastmath=CONTRACT_ARCP)
def scattering_r_mu_params(i_r: int, i_mu: int, bottom: float, top: float, n_r: int,
                           n_mu: int) -> tuple[float, float, bool]:
    """(r, mu, hits_ground) of texel indices (i_r, i_mu) of the scattering tables (the sky half inverted by
    bisection in the zenith angle)."""
    big_h = math.sqrt(top * top - bottom * bottom)
    rho = big_h * i_r / (n_r - 1)
    r = math.sqrt(rho * rho + bottom * bottom)
    half = n_mu // 2
    if i_mu < half:
        x = 1.0 - i_mu / (half - 1)
        d_min = r - bottom
        d_max = rho
        d = d_min + x * (d_max - d_min)
        if d <= 0.0:
            return r, -1.0, True
        mu = -(rho * rho + d * d) / (2.0 * r * d)
        return r, clamp(mu, -1.0, 1.0), True
    theta_h = acos_table(-rho / r)
    x = (i_mu - half) / (half - 1)
    if x <= 0.0:
        return r, 1.0, False
    if x >= 1.0:
        return r, clamp(-rho / r, -1.0, 1.0), False  # the horizon itself (cos of acos_table is 2e-8 off)
    lo, hi = 0.0, theta_h
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if _sky_mu_x(r, math.cos(mid), bottom, top) < x:
            lo = mid
        else:
            hi = mid
    return r, clamp(math.cos(0.5 * (lo + hi)), -1.0, 1.0), False


@helper(fastmath=CONTRACT_ARCP)
def scattering_mu_s_param(i_mu_s: int, bottom: float, top: float, mu_s_min: float, n_mu_s: int) -> float:
    """``mu_s`` of texel index ``i_mu_s``; inverse of :func:`scattering_mu_s_coord` (bisection in the angle)."""
    x = float(i_mu_s)
    theta_max = acos_table(mu_s_min)
    if i_mu_s <= 0:
        return mu_s_min
    if i_mu_s >= n_mu_s - 1:
        return 1.0
    big_a = _mu_s_a(mu_s_min, bottom, top)
    lo, hi = 0.0, theta_max  # coordinate decreases with the angle
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if scattering_mu_s_coord_a(math.cos(mid), bottom, top, big_a, theta_max, n_mu_s) > x:
            lo = mid
        else:
            hi = mid
    return clamp(math.cos(0.5 * (lo + hi)), -1.0, 1.0)


@helper(fastmath=CONTRACT_ARCP)
def nu_range(mu: float, mu_s: float) -> tuple[float, float]:
    """Possible view-sun cosines for view and sun zenith cosines ``mu``, ``mu_s``."""
    s = math.sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 0.0))
    return max(mu * mu_s - s, -1.0), min(mu * mu_s + s, 1.0)


@helper(fastmath=CONTRACT_ARCP)
def scattering_params(i_r: int, i_mu: int, i_mu_s: int, i_nu: int, bottom: float, top: float, mu_s_min: float,
                      n_r: int, n_mu: int, n_mu_s: int, n_nu: int) -> tuple[float, float, float, float, bool]:
    """(r, mu, mu_s, nu, hits_ground) of a texel of the 4D tables; ``nu`` is clamped to the values that the
    texel's ``mu`` and ``mu_s`` allow."""
    r, mu, hits = scattering_r_mu_params(i_r, i_mu, bottom, top, n_r, n_mu)
    mu_s = scattering_mu_s_param(i_mu_s, bottom, top, mu_s_min, n_mu_s)
    return r, mu, mu_s, scattering_nu_param(i_nu, mu, mu_s, n_nu), hits
