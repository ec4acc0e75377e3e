"""Rendering from the precomputed tables (Bruneton & Neyret 2008, Sec. 5), vectorised over rays with numba.

All kernels take positions [m] in a planet-centred frame, unit directions in the same frame, and one sun
direction per ray; they return spectral quantities at the table wavelengths.

* :func:`sky_kernel` - radiance seen along each ray: inscattered light ``S[L]`` (single Rayleigh and single
  Mie with their phase functions applied here, multiple scattering) and, where the ray meets the
  planet, the ground ``R[L0] + R^[L*]`` (Eqs. 10, 14) seen through the atmosphere (Eq. 16). An optional
  shadowed length at the near end of each ray gives light shafts by Eq. 18.
* :func:`observer_kernel` - the same radiance from one observer inside the atmosphere, from 2D slices of the
  4D tables at the observer's radius and sun (:func:`observer_slices`), optionally projected to XYZ: the same
  values with 4 table reads per ray instead of 16 (and 3 channels instead of 16 for colour); in twilight the
  caller may give the single scattering computed at the observer's own sun on a finer azimuth axis instead of the
  stored texels (``singles``; :meth:`.PrecomputedAtmosphere._twilight_singles`).
* :func:`aerial_kernel` - transmittance and inscattered radiance between a camera and a point (Eq. 16's
  last two terms, ``S|x - T(x, xs) S|xs``), with an optional shadowed length at the far end (Eq. 17).
* :func:`irradiance_kernel` - sun and sky irradiance on a surface of any normal (Eq. 14's ambient occlusion
  ``(1 + n.n_bar) / 2`` for the sky part).
* :func:`sun_kernel` - transmittance to the sun (times the visible fraction of its disc) from any position.

Reference: [Bruneton2008].
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import CONTRACT_ARCP, helper, inline, kernel
from .geometry import (
    MU_S_LIMIT_TOLERANCE,
    MU_S_SPLIT,
    acos_table,
    azimuth_four_point,
    azimuth_lagrange,
    azimuth_read_weights,
    bilinear_weights,
    clamp,
    distance_to_bottom,
    distance_to_boundary,
    ground_cell_rows_apart,
    ground_mu_unit,
    horizon_constants,
    in_earth_shadow,
    irradiance_coord,
    lerp_index,
    log_cubic_nodes,
    log_cubic_value,
    log_lerp_weight,
    log_quadratic_weight,
    point_along_ray,
    ray_hits_ground,
    refined_mu_s_count,
    scattering_mu_s_param,
    scattering_nu_azimuth,
    scattering_nu_coord,
    scattering_r_mu_coord,
    sky_mu_unit,
    transmittance_coord,
)
from .parallel import parallel_for
from .sampling import (
    TABLE_PHASE,
    aerosol_phase,
    bilinear_read,
    irradiance_lookup,
    irradiance_read,
    lookup4_cell,
    lookup4_cell_azimuth,
    lookup4_cell_spectral,
    lookup4_cell_weighted,
    lookup4_cell_weighted_spectral,
    mu_s_nu_cell,
    multiple_lobe,
    phase_table_values,
    r_mu_cell,
    r_mu_s_cell,
    rayleigh_phase,
    shadow_exit_altitudes,
    shadow_exit_altitudes_cos,
    shadow_ratios_fast,
    transmittance_ratio,
    transmittance_segment,
    transmittance_to_sun,
    transmittance_to_top,
)

PI = math.pi
#: Half-width, in mu, of the band around the horizon where two rays just above and below it are blended
#: (Bruneton's 2017 rewrite): the inscatter difference S|x - T S|xs loses precision there.
HORIZON_EPSILON = 0.004


@helper(fastmath=CONTRACT_ARCP)
def _enter_atmosphere(px, py, pz, vx, vy, vz, top):
    """Move a point outside the atmosphere to where the ray enters it: (x, y, z, distance, hits)."""
    r2 = px * px + py * py + pz * pz
    if r2 <= top * top:
        return px, py, pz, 0.0, True
    rmu = px * vx + py * vy + pz * vz
    disc = rmu * rmu - r2 + top * top
    if disc < 0.0 or rmu >= 0.0:
        return px, py, pz, 0.0, False
    d = -rmu - math.sqrt(disc)
    if d < 0.0:
        return px, py, pz, 0.0, False
    return px + d * vx, py + d * vy, pz + d * vz, d, True


@helper(fastmath=CONTRACT_ARCP)
def _inscatter(ray, mie, mult, r, mu, mu_s, nu, hits, bottom, top, mu_s_min, cells, lobe, p_r, p_m, p_m_spec,
               profiles, counts, out):
    """Inscattered radiance ``S_R P_R + S_M P_M + S_multiple`` from the tables at a point, into ``out``
    (``p_r``, ``p_m``: phase functions at ``nu``; ``p_m_spec``, if not empty, the aerosol phase per wavelength,
    used instead of ``p_m``; ``lobe``: the weight of :func:`.sampling.multiple_lobe`, by which the multiple
    scattering is stored divided and which it is multiplied by here at ``nu``); zero below the sun-zenith limit.

    Along the azimuth (nu) the single-scattering tables are interpolated log-linearly (:func:`.sampling.lookup4_cell`)
    and the multiple scattering through four azimuth texels (:func:`.sampling.lookup4_cell_azimuth`), except the
    single-scattering tables where the point lies in the Earth's shadow (:func:`.geometry.in_earth_shadow`, one
    test): there with the weights of :func:`.sampling.shadow_nu_weights` (the rule of the second order's scattering
    density; the Rayleigh and aerosol density profiles ``profiles[0]``, ``profiles[1]`` of
    :func:`.compute.density_profiles`, ``counts`` their layers): each texel's light rescaled from the density where
    its ray leaves the shadow to the density where the query's ray leaves it (at most 1), interpolated linearly.
    Measured on the single scattering against the independent integral of ``tests/precomputed_reference.py``
    (docs/accuracy.md, "Low sun"). The log-linear weight of the rescaled values is not used: where a texel's ray
    leaves the shadow higher than the query's its factor is capped at 1 and the rescaled values still differ by 10
    to 100 times, and the geometric interpolation of such a pair falls far below the light of the nearer texel
    (Earth, sun -6 deg, 2 deg / 90 deg, 560 nm: -77 %, against +10 % linear; measured)."""
    for k in range(out.shape[0]):
        out[k] = 0.0
    if mu_s < mu_s_min - MU_S_LIMIT_TOLERANCE:
        return
    mu_s = max(mu_s, mu_s_min)
    n_r, n_mu, n_s, n_n, _ = ray.shape
    i_r, w_r, i_m0, w_m0, i_m1, w_m1 = r_mu_cell(r, mu, hits, bottom, top, n_r, n_mu)
    i_s, w_s, i_n, w_n = mu_s_nu_cell(mu, mu_s, nu, bottom, top, mu_s_min, n_s, n_n, cells)
    if in_earth_shadow(r, mu_s, bottom):
        h_q, h_0, h_1 = shadow_exit_altitudes(r, mu, mu_s, nu, i_n, n_n, bottom, top)
        a, b = shadow_ratios_fast(h_q, h_0, h_1, profiles[0], counts[0])
        lookup4_cell_weighted(ray, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, (1.0 - w_n) * a, w_n * b, p_r, out)
        a, b = shadow_ratios_fast(h_q, h_0, h_1, profiles[1], counts[1])
        if p_m_spec.shape[0]:
            lookup4_cell_weighted_spectral(mie, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, (1.0 - w_n) * a,
                                           w_n * b, p_m_spec, out)
        else:
            lookup4_cell_weighted(mie, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, (1.0 - w_n) * a, w_n * b, p_m,
                                  out)
    else:
        lookup4_cell(ray, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, w_n, p_r, out)
        if p_m_spec.shape[0]:
            lookup4_cell_spectral(mie, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, w_n, p_m_spec, out)
        else:
            lookup4_cell(mie, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, w_n, p_m, out)
    lookup4_cell_azimuth(mult, i_r, w_r, i_m0, w_m0, i_m1, w_m1, i_s, w_s, i_n, w_n, multiple_lobe(nu, lobe), out)


@helper(fastmath=CONTRACT_ARCP)
def _sun_cos_factor(mu, alpha):
    """Cosine factor averaged over the solar disc (0 below the horizon, smooth across it)."""
    if mu < -alpha:
        return 0.0
    if mu > alpha:
        return mu
    return (mu + alpha) * (mu + alpha) / (4.0 * alpha)


@inline(fastmath=CONTRACT_ARCP)
def _ground_coords(px, py, pz, vx, vy, vz, sx, sy, sz, r, mu, bottom, top, alpha, n_tr, n_tmu, n_er, n_emu):
    """Table coordinates of the ground term of :func:`_ground_radiance` for the ray from (px, py, pz) [m] (radius
    ``r``, view zenith cosine ``mu``) along the unit (vx, vy, vz) that meets the ground, towards the unit sun
    (sx, sy, sz): index positions of the transmittance from the ground point and from the ray's origin along the
    reversed ray (``T(x, y) = T(y, -v) / T(x, -v)``, Sec. 4; transmittance table n_tr x n_tmu), of the sky
    irradiance at the ground point's sun zenith (irradiance table n_er x n_emu) and of the transmittance towards
    the sun there, and the sun's cosine factor (averaged over its disc of angular radius ``alpha`` [rad]).
    Branches are short and side-effect free, so loops over rays vectorise."""
    d = distance_to_bottom(r, mu, bottom)
    r_d, mu_d = point_along_ray(r, mu, d, bottom, top)
    pa_r, pa_mu = transmittance_coord(r_d, -mu_d, bottom, top, n_tr, n_tmu)
    pb_r, pb_mu = transmittance_coord(r, -mu, bottom, top, n_tr, n_tmu)
    gx = px + d * vx
    gy = py + d * vy
    gz = pz + d * vz
    mu_s_g = clamp((gx * sx + gy * sy + gz * sz) / math.sqrt(gx * gx + gy * gy + gz * gz), -1.0, 1.0)
    pe_r, pe_mu = irradiance_coord(bottom, mu_s_g, bottom, top, n_er, n_emu)
    ps_r, ps_mu = transmittance_coord(bottom, mu_s_g, bottom, top, n_tr, n_tmu)
    return pa_r, pa_mu, pb_r, pb_mu, pe_r, pe_mu, ps_r, ps_mu, _sun_cos_factor(mu_s_g, alpha)


@helper(fastmath=CONTRACT_ARCP)
def _ground_from_coords(transmittance, irradiance, albedo, solar, pa_r, pa_mu, pb_r, pb_mu, pe_r, pe_mu, ps_r, ps_mu,
                        cf, t, tmp, e_sky, e_sun, out):
    """The ground's radiance (Eqs. 10, 14) seen through the atmosphere (Eq. 16) from the coordinates of
    :func:`_ground_coords`, into ``out``; leaves the transmittance to the ground in ``t``; the sky irradiance read
    with each wavelength's own weight along the sun zenith (:func:`.sampling.irradiance_read`)."""
    bilinear_read(transmittance, pa_r, pa_mu, t)
    bilinear_read(transmittance, pb_r, pb_mu, tmp)
    transmittance_ratio(t, tmp)
    irradiance_read(irradiance, pe_r, pe_mu, e_sky)
    bilinear_read(transmittance, ps_r, ps_mu, e_sun)
    for k in range(out.shape[0]):
        out[k] = t[k] * albedo[k] / PI * (solar[k] * e_sun[k] * cf + e_sky[k])


@helper(fastmath=CONTRACT_ARCP)
def _ground_radiance(transmittance, irradiance, albedo, solar, px, py, pz, vx, vy, vz, sx, sy, sz, r, mu, bottom, top,
                     alpha, t, tmp, e_sky, e_sun, out):
    """Radiance of the Lambertian ground lit by the sun and the sky (Eqs. 10, 14) where the ray from (px, py, pz)
    [m] along (vx, vy, vz) meets it, seen through the atmosphere (Eq. 16), into ``out``; leaves the transmittance
    to the ground in ``t``."""
    c = _ground_coords(px, py, pz, vx, vy, vz, sx, sy, sz, r, mu, bottom, top, alpha, transmittance.shape[0],
                       transmittance.shape[1], irradiance.shape[0], irradiance.shape[1])
    _ground_from_coords(transmittance, irradiance, albedo, solar, c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7],
                        c[8], t, tmp, e_sky, e_sun, out)


@helper(fastmath=CONTRACT_ARCP)
def _ground_coords_block(m, gv, gmu, px, py, pz, sx, sy, sz, r, bottom, top, alpha, n_tr, n_tmu, n_er, n_emu, gc):
    """:func:`_ground_coords` for a block's first ``m`` ground rays (unit directions ``gv`` (3, >= m) by component,
    view zenith cosines ``gmu``) into ``gc`` (9, >= m), on SIMD lanes (ray index last: unit strides, see
    :func:`_observer_coords`)."""
    for k in range(m):
        (gc[0, k], gc[1, k], gc[2, k], gc[3, k], gc[4, k], gc[5, k], gc[6, k], gc[7, k],
         gc[8, k]) = _ground_coords(px, py, pz, gv[0, k], gv[1, k], gv[2, k], sx, sy, sz, r, gmu[k], bottom, top, alpha,
                                    n_tr, n_tmu, n_er, n_emu)


@kernel
def sky_kernel(pos, dirs, suns, shadow, transmittance, ray, mie, mult, irradiance, albedo, solar, bottom, top,
               mu_s_min, cells, g, mie_kind, lobe, phase_mu, phase_values, profiles, counts, alpha, include_ground,
               rad_out, tr_out, start, stop):
    """Radiance [W m^-2 sr^-1 nm^-1] and transmittance along rays ``start..stop``; see the module docstring.

    Writes ``rad_out`` and ``tr_out`` (n_rays, n_wavelengths), which the caller initialises to 0 and 1
    (the values of rays that miss the atmosphere). ``lobe``: the weight of :func:`.sampling.multiple_lobe`. A
    tabulated aerosol phase (``mie_kind``
    :data:`.sampling.TABLE_PHASE`) is read per wavelength from ``phase_mu``, ``phase_values``; ``profiles``,
    ``counts``: the density profiles of :func:`.compute.density_profiles` (the Earth's shadow, :func:`_inscatter`);
    """
    n_l = transmittance.shape[2]
    p_m_spec = np.empty(n_l if mie_kind == TABLE_PHASE else 0)
    c = np.empty(n_l)
    t = np.empty(n_l)
    tmp = np.empty(n_l)
    e_sky = np.empty(n_l)
    e_sun = np.empty(n_l)
    ground = np.empty(n_l)
    for q in range(start, stop):
        vx, vy, vz = dirs[q, 0], dirs[q, 1], dirs[q, 2]
        sx, sy, sz = suns[q, 0], suns[q, 1], suns[q, 2]
        px, py, pz, _, inside = _enter_atmosphere(pos[q, 0], pos[q, 1], pos[q, 2], vx, vy, vz, top)
        if not inside:
            continue
        r = math.sqrt(px * px + py * py + pz * pz)
        rc = clamp(r, bottom, top)
        mu = clamp((px * vx + py * vy + pz * vz) / r, -1.0, 1.0)
        mu_s = clamp((px * sx + py * sy + pz * sz) / r, -1.0, 1.0)
        nu = clamp(vx * sx + vy * sy + vz * sz, -1.0, 1.0)
        hits = ray_hits_ground(rc, mu, bottom)
        p_r = rayleigh_phase(nu)
        p_m = aerosol_phase(nu, g, mie_kind) if mie_kind != TABLE_PHASE else 0.0
        if p_m_spec.shape[0]:
            phase_table_values(phase_mu, phase_values, nu, p_m_spec)
        l_sh = shadow[q]
        if l_sh > 0.0:
            # Eq. 18: the first l_sh metres are in shadow; inscatter starts at xs = x + l v.
            l_sh = min(l_sh, distance_to_boundary(rc, mu, hits, bottom, top))
            r_s, mu_ss = point_along_ray(rc, mu, l_sh, bottom, top)
            mu_s_s = clamp((rc * mu_s + l_sh * nu) / r_s, -1.0, 1.0)
            if r_s >= top and mu_ss > 0.0:
                for k in range(n_l):
                    c[k] = 0.0
            else:
                _inscatter(ray, mie, mult, r_s, mu_ss, mu_s_s, nu, hits, bottom, top, mu_s_min, cells, lobe, p_r, p_m,
                           p_m_spec, profiles, counts, c)
            transmittance_segment(transmittance, rc, mu, l_sh, hits, bottom, top, t, tmp)
            for k in range(n_l):
                c[k] *= t[k]
        else:
            _inscatter(ray, mie, mult, rc, mu, mu_s, nu, hits, bottom, top, mu_s_min, cells, lobe, p_r, p_m, p_m_spec,
                       profiles, counts, c)
        for k in range(n_l):
            rad_out[q, k] = c[k]
        if hits and include_ground:
            _ground_radiance(transmittance, irradiance, albedo, solar, px, py, pz, vx, vy, vz, sx, sy, sz, rc,
                             mu, bottom, top, alpha, t, tmp, e_sky, e_sun, ground)
            for k in range(n_l):
                tr_out[q, k] = t[k]
                rad_out[q, k] += ground[k]
        elif hits:
            transmittance_segment(transmittance, rc, mu, distance_to_bottom(rc, mu, bottom), True, bottom, top, t,
                                  tmp)
            for k in range(n_l):
                tr_out[q, k] = t[k]
        else:
            transmittance_to_top(transmittance, rc, mu, bottom, top, t)
            for k in range(n_l):
                tr_out[q, k] = t[k]


@helper(fastmath=CONTRACT_ARCP)
def observer_two_rows(r, bottom, top, n_r):
    """True if an observer at radius ``r`` [m] lies strictly within the cell of the 4D tables' ``n_r`` rows that
    touches the ground (below the first row above it): its rays that miss the ground read each row at its own ``mu``
    coordinate (:func:`.geometry.scattering_r_mu_rows`), so the observer slices hold the two rows' shares apart."""
    p_r, _ = scattering_r_mu_coord(r, 1.0, False, bottom, top, n_r, 4)
    return 0.0 < p_r < 1.0 and ground_cell_rows_apart(bottom, top, n_r)


@helper(fastmath=CONTRACT_ARCP)
def _sub_texel(y, lg, k, m, i, w, last, j0, c0, c1, c2, c3):
    """Value of a sub-texel at the fraction ``w`` of the sun-zenith cell ``i``, ``i + 1`` of one column (nu ``k``,
    wavelength ``m``) from the stored texels ``0 .. last``, ``y[t, k, m]`` with their logarithms
    ``lg[t, k, m]`` (any value where ``y`` is not positive): :func:`.geometry.log_cubic_value` over the four texels
    ``j0 .. j0 + 3`` (weights ``c0 .. c3`` of :func:`.geometry.log_cubic_nodes`; ``j0`` negative where there are
    fewer than four) where they are positive; otherwise the three-point Lagrange formula in the logarithm over the
    texels ``i .. i + 2`` (:func:`.geometry.log_quadratic_weight`; a texel below the cell in the Earth's shadow),
    kept between the cell's two values; the geometric interpolation where only the cell's two are positive; where the
    cell's lower texel is not positive (a single-scattering column whose sunlit part begins within the cell) the
    log-linear extrapolation of the texels ``i + 1``, ``i + 2`` into the cell, at most the linear read
    ``w y[i + 1]`` (the sky falls faster, not slower, towards the shadow: a linear read there was +55 to +105 %
    against the Monte Carlo, docs/accuracy.md, "Low sun"); linear where nothing else applies."""
    a = y[i, k, m]
    b = y[i + 1, k, m]
    c = y[i + 2, k, m] if i + 2 <= last else 0.0
    if j0 >= 0 and y[j0, k, m] > 0.0 and y[j0 + 1, k, m] > 0.0 and y[j0 + 2, k, m] > 0.0 and y[j0 + 3, k, m] > 0.0:
        return log_cubic_value(a, b, lg[j0, k, m], lg[j0 + 1, k, m], lg[j0 + 2, k, m], lg[j0 + 3, k, m],
                               c0, c1, c2, c3)
    if a > 0.0 and b > 0.0:
        if c > 0.0:  # the irradiance read's rule, the middle texel i + 1
            return a + log_quadratic_weight(a, b, c, w - 1.0) * (b - a)
        return math.exp((1.0 - w) * lg[i, k, m] + w * lg[i + 1, k, m])
    if b > 0.0 and c > b:
        return min(w * b, b * math.exp((1.0 - w) * (lg[i + 1, k, m] - lg[i + 2, k, m])))
    return a + w * (b - a)


@kernel
def refine_mu_s_kernel(table, cells, j_lo, given, out, start, stop):
    """Columns ``j_lo .. j_lo + out.shape[2] - 1`` of the sun-zenith axis of ``table`` (n_r, n_mu, n_mu_s, n_nu,
    n_wavelengths) with its first ``cells`` cells split into :data:`.geometry.MU_S_SPLIT` sub-cells, into ``out``
    (n_r, n_mu, n_columns, n_nu, n_wavelengths), rows ``start..stop`` of the flattened (r, mu) axes: a stored texel
    is copied; a sub-texel at the fraction ``w`` of its cell holds :func:`_sub_texel` of the texels ``0 .. cells +
    1`` (with the default split, :func:`.geometry.twilight_cells`, those below the horizon and the first two above
    it: in the last cell below the horizon a stencil that ended below the horizon was 2-3 times further from tables
    of 94 texels, 90th percentile, than one that takes the next texel), each (nu, wavelength) its own. The
    logarithms of those texels are taken once per row. Where ``given`` is not empty (n_r, n_mu, (MU_S_SPLIT - 1)
    cells, n_nu, n_wavelengths: the sub-texels' values computed, in the order of the refined axis), the sub-texels
    are those values instead."""
    n_mu, n_nu, n_l = table.shape[1], table.shape[3], table.shape[4]
    n_out = out.shape[2]
    split = MU_S_SPLIT * cells
    last = min(cells + 1, table.shape[2] - 1)  # the stencils' texels: up to the second above the horizon
    y = np.empty((last + 1, n_nu, n_l))
    lg = np.empty((last + 1, n_nu, n_l))
    need = j_lo < split and given.shape[2] == 0
    # the stored texels the asked columns' stencils and fall-backs read (all of them for the whole axis)
    i_hi = min((j_lo + n_out - 1) // MU_S_SPLIT, cells - 1)
    t_lo = max(0, min(j_lo // MU_S_SPLIT - 1, last - 3))
    t_hi = min(last, i_hi + 3)
    for q in range(start, stop):
        i_r = q // n_mu
        i_m = q % n_mu
        if need:
            for t in range(t_lo, t_hi + 1):
                for k in range(n_nu):
                    for m in range(n_l):
                        v = np.float64(table[i_r, i_m, t, k, m])
                        y[t, k, m] = v
                        lg[t, k, m] = math.log(v) if v > 0.0 else 0.0
        for jj in range(n_out):
            j = j_lo + jj
            if j >= split or j % MU_S_SPLIT == 0:
                src = j - (MU_S_SPLIT - 1) * cells if j >= split else j // MU_S_SPLIT
                for k in range(n_nu):
                    for m in range(n_l):
                        out[i_r, i_m, jj, k, m] = table[i_r, i_m, src, k, m]
                continue
            i = j // MU_S_SPLIT
            w = (j % MU_S_SPLIT) / MU_S_SPLIT
            if given.shape[2] > 0:
                g = i * (MU_S_SPLIT - 1) + j % MU_S_SPLIT - 1
                for k in range(n_nu):
                    for m in range(n_l):
                        out[i_r, i_m, jj, k, m] = given[i_r, i_m, g, k, m]
                continue
            if i >= 1 and last >= 4:
                # texels 1 .. last: the tables' last texel (at mu_s_min) is left out of the stencils of the cells
                # above it (in the cell -9.65..-7.63 deg of the default tables the 90th percentile against tables
                # of 94 texels fell from 35-62 % to 2-5 %, Rayleigh and multiple scattering)
                j0, c0, c1, c2, c3 = log_cubic_nodes(i - 1, w, last)
                j0 += 1
            elif last >= 3:
                j0, c0, c1, c2, c3 = log_cubic_nodes(i, w, last + 1)
            else:
                j0, c0, c1, c2, c3 = -1, 0.0, 0.0, 0.0, 0.0
            for k in range(n_nu):
                for m in range(n_l):
                    out[i_r, i_m, jj, k, m] = _sub_texel(y, lg, k, m, i, w, last, j0, c0, c1, c2, c3)


def radius_layer(table, i_r):
    """A 4D table at radius index ``i_r``: (n_mu, n_mu_s, n_nu, n_wavelengths) float32 (a
    :class:`.storage.HalfTable`'s decoded layer, which it keeps for the next calls)."""
    return table.radius_layer(i_r) if hasattr(table, "radius_layer") else np.asarray(table[i_r], dtype=np.float32)


def sub_texel_suns(bottom, top, mu_s_min, n_mu_s, cells):
    """Zenith cosines of the suns of the sub-texels of a sun-zenith axis of ``n_mu_s`` texels whose first ``cells``
    cells are split into :data:`.geometry.MU_S_SPLIT` (:func:`refine_sun_zenith`), in the order of the refined
    axis ((MU_S_SPLIT - 1) cells of them): the sub-texel at the fraction ``m / MU_S_SPLIT`` of cell ``i`` is the
    texel ``MU_S_SPLIT i + m`` of an axis of ``MU_S_SPLIT (n_mu_s - 1) + 1`` texels (the mapping is the same
    fraction of either axis, :func:`.geometry.scattering_mu_s_coord`). ``bottom``, ``top`` [m]."""
    n_fine = MU_S_SPLIT * (n_mu_s - 1) + 1
    return np.array([scattering_mu_s_param(MU_S_SPLIT * i + m, bottom, top, mu_s_min, n_fine)
                     for i in range(cells) for m in range(1, MU_S_SPLIT)], dtype=np.float64)


def refine_sun_zenith(table, cells, columns=None, out=None, sub_texels=None):
    """A 4D scattering table (n_r, n_mu, n_mu_s, n_nu, n_wavelengths; float32, or a :class:`.storage.HalfTable`,
    decoded) refined along the sun zenith for the rendering lookups: its first ``cells`` cells (those below and the
    one across the horizon, :func:`.geometry.twilight_cells`) split into :data:`.geometry.MU_S_SPLIT` sub-cells
    (:func:`refine_mu_s_kernel`), float32, read with :func:`.geometry.refined_mu_s_cell`; ``columns`` (start,
    stop), if given, only those columns of the refined axis; written into ``out`` if given (float32, C-contiguous,
    of the result's shape); ``sub_texels`` (n_r, n_mu, (MU_S_SPLIT - 1) cells, n_nu, n_wavelengths), if given, the
    sub-texels' values computed at their suns (:func:`sub_texel_suns`; the single scattering,
    :func:`.compute.stored_single_scattering`), which then replace the rule. The stored texels keep their values,
    so a read above the split cells is the stored table's to the bit.

    Why: in twilight the sky falls by 2-5 times across one cell of the default 32 sun-zenith texels and the slope
    of its logarithm turns within a few cells, so no linear read between two texels follows it (+23 to +34 %
    median between the texels from -7 to -4.5 deg against tables of 94 texels); the four-point rule in the
    logarithm follows it to 0.6-0.7 % there (docs/accuracy.md, "Low sun"). Done as data, once per table (or per
    observer's two radius rows), every lookup stays a linear read: the same cost per ray, and the real-time
    textures folded to colour read as the spectra do. The library gives the single-scattering tables their
    sub-texels computed (``sub_texels``): where the Earth's shadow reaches a column within a cell (below the
    horizon, and across it for the ground's own point) no rule through the texels follows the single scattering
    (the four-point rule -52 to +18 %, the linear read +8 to +18 %, against the 94-texel tables opposite a sun on
    the horizon, clear air, views 0.2-2 deg)."""
    values = np.ascontiguousarray(table[:] if not isinstance(table, np.ndarray) else table, dtype=np.float32)
    n_r, n_mu, n_s, n_nu, n_l = values.shape
    n_f = refined_mu_s_count(n_s, cells)
    lo, hi = (0, n_f) if columns is None else (int(columns[0]), int(columns[1]))
    if not 0 <= lo < hi <= n_f:
        raise ValueError(f"columns {columns} outside the refined axis of {n_f} texels")
    shape = (n_r, n_mu, hi - lo, n_nu, n_l)
    if out is None:
        out = np.empty(shape, dtype=np.float32)
    elif out.shape != shape or out.dtype != np.float32 or not out.flags.c_contiguous:
        raise ValueError(f"out must be a C-contiguous float32 array of shape {shape}")
    if sub_texels is None:
        given = np.empty((0, 0, 0, 0, 0), dtype=np.float32)
    else:
        given = np.ascontiguousarray(sub_texels, dtype=np.float32)
        want = (n_r, n_mu, (MU_S_SPLIT - 1) * cells, n_nu, n_l)
        if given.shape != want:
            raise ValueError(f"sub_texels must have shape {want}; got {given.shape}")
    parallel_for(refine_mu_s_kernel, n_r * n_mu, values, int(cells), lo, given, out, grain=64)
    return out


@kernel(fastmath=CONTRACT_ARCP)
def refine_azimuth_kernel(values, out):
    """``values`` (n_mu, n_nu, C + 1) along an azimuth axis of ``n_nu`` texels read at the ``n_f`` texels of a finer
    axis (``out`` (n_mu, n_f, C + 1); ``n_f - 1`` a multiple of ``n_nu - 1``, so that every texel of the coarse axis
    is one of the fine) by the lookups' read of the multiple scattering along the azimuth
    (:func:`.geometry.azimuth_four_point`, :func:`.geometry.azimuth_read_weights`, weights from channel C, the
    middle wavelength): at the coarse texels the values themselves."""
    n_mu, n_nu, n_ch = values.shape
    n_f = out.shape[1]
    step = (n_f - 1) // (n_nu - 1)
    for f in range(n_f):
        i_n = min(f // step, n_nu - 2)
        w = (f - i_n * step) / step
        j0, j3, l0, l1, l2, l3 = azimuth_four_point(i_n, w, n_nu)
        for m in range(n_mu):
            w0, w1, w2, w3 = azimuth_read_weights(values[m, j0, n_ch - 1], values[m, i_n, n_ch - 1],
                                                  values[m, i_n + 1, n_ch - 1], values[m, j3, n_ch - 1], w, l0,
                                                  l1, l2, l3)
            for c in range(n_ch):
                out[m, f, c] = (w0 * values[m, j0, c] + w1 * values[m, i_n, c] + w2 * values[m, i_n + 1, c]
                                + w3 * values[m, j3, c])


def observer_slices(single_rayleigh, single_mie, multiple, r, mu_s, bottom, top, mu_s_min, cells, projection,
                    layers=None, singles=None):
    """The 4D inscattering tables at one observer radius ``r`` [m] and sun zenith cosine ``mu_s``: an array
    (2, n_mu, n_nu, C + 1, 4) holding, for each channel, single Rayleigh, single Mie and multiple scattering over the
    view axes (and a zero, so that each texel's three values are one aligned 32-byte load), each
    ``table @ projection.T`` (``projection`` (C, n_wavelengths): the identity for spectra, the XYZ matrix for
    colour); channel C (the last of C + 1) holds each table at its middle wavelength, from which the azimuth weights
    of the lookup are computed (:func:`.sampling.nu_weight`; the multiple scattering's four,
    :func:`_observer_azimuth_weights`). ``[0]`` holds the slices and ``[1]`` zeros, except
    for an observer within the cell touching the ground (:func:`observer_two_rows`): there ``[0]`` and ``[1]`` hold
    the shares of the lower and the upper row, which the lookup reads each at its own ``mu`` coordinate (the ground
    half of the ``mu`` axis at the same coordinate in both). The tables are the stored ones; their two radius rows
    around the observer are refined along the sun zenith here (:func:`refine_sun_zenith`, ``cells`` split cells,
    only the two columns read, every sub-texel from the rule: the single scattering's computed sub-texels need the
    atmosphere, which the tables alone do not carry); or, with ``layers`` (a function of the table's index, 0 single
    Rayleigh, 1 single Mie, 2 multiple, and a radius index), its columns read from the refined radius layers it
    returns (n_mu, n_mu_s refined, n_nu, n_wavelengths), which a caller may keep: the library passes its own
    (:meth:`.PrecomputedAtmosphere._lookup_layer`), as the other lookups read its whole refined tables.

    The lookup is linear in ``r``, ``mu`` and ``mu_s``, so fixing the ``r`` and ``mu_s`` weights once and
    interpolating the slice in (``mu``, ``nu``) gives the same values as the 4D lookup; its weight along ``nu`` is
    one for all wavelengths (from the middle one), so the lookup is linear in the table values and the inscattered
    radiance a sum of table values times wavelength-independent phase factors: projecting the slice first gives the
    same XYZ as projecting each looked-up spectrum (Bruneton's 2017 rewrite folds its tables to luminance the same
    way). Zero when ``mu_s`` is below ``mu_s_min`` (no data below the tables' sun limit;
    :data:`.geometry.MU_S_LIMIT_TOLERANCE` for rounding).

    ``singles`` (twilight; :meth:`.PrecomputedAtmosphere._twilight_singles`): the single scattering (Rayleigh,
    aerosol) of the two radius rows computed at the observer's own ``mu_s`` on a finer azimuth axis, each
    (2, n_mu, n_f, n_wavelengths) float32 as the tables store it, ``n_f - 1`` a multiple of ``n_nu - 1``. The slices
    then have ``n_f`` azimuth texels: the single scattering from those rows (no read along the sun zenith), the
    multiple scattering read at the finer texels by the lookups' own azimuth rule (:func:`refine_azimuth_kernel`).
    Why: in twilight the single scattering seen from the Earth's shadow changes by tens to hundreds of times across
    one of the 8 azimuth cells, which no read through the stored texels follows (docs/accuracy.md, "Low sun").
    """
    n_r, n_mu, n_s, n_nu, _ = single_rayleigh.shape
    proj = np.asarray(projection, dtype=np.float64)
    n_c = proj.shape[0]
    n_f = n_nu if singles is None else singles[0].shape[2]
    if singles is not None and (n_f < n_nu or (n_f - 1) % (n_nu - 1)):
        raise ValueError(f"the computed single scattering's {n_f} azimuth texels must refine the tables' {n_nu}")
    out = np.zeros((2, n_mu, n_f, n_c + 1, 4))
    if mu_s < mu_s_min - MU_S_LIMIT_TOLERANCE:
        return out
    mu_s = max(mu_s, mu_s_min)
    n_f = refined_mu_s_count(n_s, cells)
    i_r, w_r, i_s, w_s, w_g = r_mu_s_cell(r, mu_s, bottom, top, mu_s_min, n_r, n_f, cells)
    half = n_mu // 2
    # within the cell touching the ground each row's share apart (out[0], out[1]), read at its own mu coordinate
    parts = (0, 1) if observer_two_rows(r, bottom, top, n_r) else (None,)
    split = MU_S_SPLIT * cells
    for j, table in enumerate((single_rayleigh, single_mie, multiple)):
        radii = [min(i, n_r - 1) for i in (i_r, i_r + 1)]
        if layers is not None:  # the caller's refined radius layers
            rows2 = [layers(j, i)[:, i_s:i_s + 2] for i in radii]
        elif i_s >= split:  # above the split cells: the stored columns themselves
            s0 = i_s - (MU_S_SPLIT - 1) * cells
            rows2 = [radius_layer(table, i)[:, s0:s0 + 2] for i in radii]
        else:  # the observer's two radius rows refined along the sun zenith, in the two columns read
            rows2 = [refine_sun_zenith(radius_layer(table, i)[None], cells, (i_s, i_s + 2))[0] for i in radii]
        columns = ((0, 1.0 - w_s), (1, w_s))
        if singles is not None and j < 2:  # computed at the observer's sun: one column, the finer azimuths
            rows2 = [singles[j][a][:, None] for a in (0, 1)]
            columns = ((0, 1.0),)
        for part in parts:
            acc = np.zeros((n_mu, rows2[0].shape[2], rows2[0].shape[-1]))
            # the ground half of the mu axis with its own radius weight (.geometry.scattering_r_mu_coord)
            for rows, w in ((slice(0, half), w_g), (slice(half, n_mu), w_r)):
                for a, wa in ((0, 1.0 - w), (1, w)):
                    if part is not None and a != part:
                        continue
                    for c, wc in columns:
                        if wa * wc > 0.0:
                            acc[rows] += (wa * wc) * rows2[a][rows, c, :, :]
            k = 0 if part is None else part
            values = np.empty((n_mu, acc.shape[1], n_c + 1))
            values[:, :, :n_c] = acc @ proj.T
            values[:, :, n_c] = acc[:, :, acc.shape[-1] // 2]
            if values.shape[1] != n_f:
                refine_azimuth_kernel(values, out[k, :, :, :, j])
            else:
                out[k, :, :, :, j] = values
    return out


#: Rays per block of :func:`observer_kernel` (its buffers stay in the L1 cache).
OBSERVER_BLOCK = 256


@helper(fastmath=CONTRACT_ARCP)
def _unit_block(dirs):
    """True if every direction of the block (flat x, y, z triples) is a unit vector to 1e-12 (NaN and infinite
    ones are not)."""
    off = 0
    for k in range(dirs.shape[0] // 3):
        n2 = dirs[3 * k] * dirs[3 * k] + dirs[3 * k + 1] * dirs[3 * k + 1] + dirs[3 * k + 2] * dirs[3 * k + 2]
        off += 0 if abs(n2 - 1.0) <= 1e-12 else 1
    return off == 0


@helper(fastmath=CONTRACT_ARCP)
def _observer_coords(dirs, unit, px, py, pz, r, rc, sx, sy, sz, mu_s, bottom, top, rho, big_h, theta_h, g,
                     mie_kind, lobe, n_mu, n_nu, cell, w_mu, w_nu, nu_i, p_r, p_m, p_l, kind):
    """Table cells, weights and phase factors of a block of rays from one observer (the first pass of
    :func:`observer_kernel`; ``p_l`` the multiple scattering's :func:`.sampling.multiple_lobe` of weight
    ``lobe``); ``unit``: the block's directions are unit vectors (:func:`_unit_block`), so the
    normalisation (a square root and a division per ray) is skipped. No branch that the compiler cannot turn into
    a select, no libm call: the loop runs on SIMD lanes. Every ray gets the sky half's ``mu`` cell; ``kind``
    marks the rays that meet the ground (2), whose cell the caller replaces, and bad directions (0: zero,
    infinite or NaN); 1 for the sky. Returns the number of rays that are not sky rays.

    ``dirs`` is the block's directions as flat x, y, z triples: indexed ``dirs[k, j]``, a C-ordered (m, 3) array
    has a row length known only at run time, and LLVM then vectorises the loop only for rows of length 1 (a
    scalar loop runs for ours); with the stride a constant 3 the loads become SIMD shuffles (coordinates 27 ->
    15 ns per ray)."""
    half = n_mu // 2
    inv_r = 1.0 / r
    special = 0
    for k in range(dirs.shape[0] // 3):
        vx = dirs[3 * k]
        vy = dirs[3 * k + 1]
        vz = dirs[3 * k + 2]
        n2 = vx * vx + vy * vy + vz * vz
        ok = n2 > 0.0 and n2 < math.inf
        inv = 1.0 if unit else 1.0 / math.sqrt(n2)
        mu = clamp((px * vx + py * vy + pz * vz) * (inv * inv_r), -1.0, 1.0) if ok else 0.0
        nu = clamp((vx * sx + vy * sy + vz * sz) * inv, -1.0, 1.0) if ok else 0.0
        hits = ray_hits_ground(rc, mu, bottom)
        i_mu, wm = lerp_index(half + sky_mu_unit(rc, mu, top, rho, big_h, theta_h) * (half - 1), half, n_mu - 1)
        i_n, wn = lerp_index(scattering_nu_coord(mu, mu_s, nu, n_nu), 0, n_nu - 1)
        cell[k] = i_mu * n_nu + i_n
        w_mu[k] = wm
        w_nu[k] = wn
        nu_i[k] = i_n  # for the multiple scattering's four azimuth texels (_observer_azimuth_weights)
        p_r[k] = rayleigh_phase(nu)
        p_m[k] = aerosol_phase(nu, g, mie_kind)
        p_l[k] = multiple_lobe(nu, lobe)
        kind[k] = (2 if hits else 1) if ok else 0
        special += 0 if ok and not hits else 1
    return special


@helper(fastmath=CONTRACT_ARCP)
def _observer_row_cells(dirs, px, py, pz, r, bottom, top, n_r, n_mu, n_nu, cell, w_mu, cell1, w_mu1):
    """For an observer within the cell touching the ground (:func:`observer_two_rows`): the ``mu`` cells of a block
    of rays (flat x, y, z triples ``dirs``; cells of :func:`_observer_coords`, whose azimuth index is kept) at which
    the lower row (into ``cell``, ``w_mu``) and the upper row (``cell1``, ``w_mu1``) hold each ray's direction
    (:func:`.geometry.scattering_row_mu_coord`, as :func:`.sampling.r_mu_cell`). The caller replaces both for the
    rays that meet the ground."""
    half = n_mu // 2
    inv_r = 1.0 / r
    # the rows' constants of the mu mapping (.geometry.scattering_row_mu_coord), out of the loop: it runs on SIMD lanes
    big_h = math.sqrt(top * top - bottom * bottom)
    rho1 = big_h / (n_r - 1)
    r1 = math.sqrt(rho1 * rho1 + bottom * bottom)
    th0 = acos_table(0.0)
    th1 = acos_table(-rho1 / r1)
    for k in range(cell.shape[0]):
        vx = dirs[3 * k]
        vy = dirs[3 * k + 1]
        vz = dirs[3 * k + 2]
        n2 = vx * vx + vy * vy + vz * vz
        inv = 1.0 / math.sqrt(n2) if n2 > 0.0 and n2 < math.inf else 0.0
        mu = clamp((px * vx + py * vy + pz * vz) * (inv * inv_r), -1.0, 1.0)
        i_n = cell[k] % n_nu
        i0, w0 = lerp_index(half + sky_mu_unit(bottom, mu, top, 0.0, big_h, th0) * (half - 1), half, n_mu - 1)
        i1, w1 = lerp_index(half + sky_mu_unit(r1, mu, top, rho1, big_h, th1) * (half - 1), half, n_mu - 1)
        cell[k] = i0 * n_nu + i_n
        w_mu[k] = w0
        cell1[k] = i1 * n_nu + i_n
        w_mu1[k] = w1


@helper(fastmath=CONTRACT_ARCP)
def _observer_nu_weights(slices, slices1, two_rows, n_nu, n_c, cell, w_mu, cell1, w_mu1, w_nu, w_tab, ends):
    """The azimuth weights (:func:`.sampling.nu_weight`) of the two single-scattering tables of the observer slices
    (n_mu * n_nu, n_c + 1, 4) for a block of rays into ``w_tab[0]``, ``w_tab[1]``, from the middle wavelength in
    channel ``n_c`` (the multiple scattering's: :func:`_observer_azimuth_weights`). Two
    passes: the ends of each table's cell (linear along mu at the two nu texels) gathered into ``ends`` (2, 3, >= m,
    float32), then :func:`.geometry.log_lerp_weight` over those contiguous values in float32, which runs on SIMD
    lanes (a loop that gathers and divides at once stays scalar; measured). With ``two_rows`` the ends are the sums
    of the two rows' shares (``slices``, ``slices1``), each at its own cell (``cell``, ``w_mu`` and ``cell1``,
    ``w_mu1``: :func:`_observer_row_cells`), as :func:`.sampling.nu_weight` sums them."""
    m = cell.shape[0]
    for k in range(m):
        a = cell[k]
        b = a + n_nu
        wm = w_mu[k]
        for t in range(2):
            e0 = (1.0 - wm) * slices[a, n_c, t] + wm * slices[b, n_c, t]
            e1 = (1.0 - wm) * slices[a + 1, n_c, t] + wm * slices[b + 1, n_c, t]
            if two_rows:
                a1 = cell1[k]
                b1 = a1 + n_nu
                wm1 = w_mu1[k]
                e0 += (1.0 - wm1) * slices1[a1, n_c, t] + wm1 * slices1[b1, n_c, t]
                e1 += (1.0 - wm1) * slices1[a1 + 1, n_c, t] + wm1 * slices1[b1 + 1, n_c, t]
            ends[0, t, k] = e0
            ends[1, t, k] = e1
    for t in range(2):
        e0 = ends[0, t]
        e1 = ends[1, t]
        wt = w_tab[t]
        for k in range(m):
            wt[k] = log_lerp_weight(e0[k], e1[k], np.float32(w_nu[k]))


@helper(fastmath=CONTRACT_ARCP)
def _observer_azimuth_weights(slices, slices1, two_rows, n_nu, n_c, cell, nu_i, w_mu, cell1, w_mu1, w_nu, w4, off,
                              ends):
    """The multiple scattering's weights of its four azimuth texels (:func:`.sampling.lookup4_cell_azimuth`:
    :func:`.geometry.azimuth_four_point`, :func:`.geometry.azimuth_read_weights`) for a block of rays of the
    observer slices (n_mu * n_nu, n_c + 1, 4; the middle wavelength in channel ``n_c``) into ``w4`` (4, >= m,
    float32), and the outer texels' offsets from the cell's first into ``off`` (2, >= m; ``nu_i`` the cells'
    azimuth indices, of :func:`_observer_coords`); each texel's value linear
    along mu at the ray's cell, with ``two_rows`` the sum of the two rows' shares (``slices1`` at ``cell1``,
    ``w_mu1``), as :func:`.sampling.lookup4_cell_azimuth` sums the rows. Two passes, as
    :func:`_observer_nu_weights`: the four values gathered into ``ends`` (4, >= m, float32), then the weights in
    float32 over those contiguous values (branch-free; the same rule, rounded to float32)."""
    m = cell.shape[0]
    for k in range(m):
        a = cell[k]
        i_n = nu_i[k]
        o0 = -1 if i_n > 0 else 1  # the texel before the first is the second
        o3 = 2 if i_n < n_nu - 2 else 0  # the one after the last is the one before it
        off[0, k] = o0
        off[1, k] = o3
        wm = w_mu[k]
        b = a + n_nu
        v0 = (1.0 - wm) * slices[a + o0, n_c, 2] + wm * slices[b + o0, n_c, 2]
        v1 = (1.0 - wm) * slices[a, n_c, 2] + wm * slices[b, n_c, 2]
        v2 = (1.0 - wm) * slices[a + 1, n_c, 2] + wm * slices[b + 1, n_c, 2]
        v3 = (1.0 - wm) * slices[a + o3, n_c, 2] + wm * slices[b + o3, n_c, 2]
        if two_rows:
            a1 = cell1[k]
            b1 = a1 + n_nu
            wm1 = w_mu1[k]
            v0 += (1.0 - wm1) * slices1[a1 + o0, n_c, 2] + wm1 * slices1[b1 + o0, n_c, 2]
            v1 += (1.0 - wm1) * slices1[a1, n_c, 2] + wm1 * slices1[b1, n_c, 2]
            v2 += (1.0 - wm1) * slices1[a1 + 1, n_c, 2] + wm1 * slices1[b1 + 1, n_c, 2]
            v3 += (1.0 - wm1) * slices1[a1 + o3, n_c, 2] + wm1 * slices1[b1 + o3, n_c, 2]
        ends[0, k] = v0
        ends[1, k] = v1
        ends[2, k] = v2
        ends[3, k] = v3
    e0 = ends[0]
    e1 = ends[1]
    e2 = ends[2]
    e3 = ends[3]
    for k in range(m):
        t = np.float32(w_nu[k])
        l0, l1, l2, l3 = azimuth_lagrange(t)
        w0, w1, w2, w3 = azimuth_read_weights(e0[k], e1[k], e2[k], e3[k], t, l0, l1, l2, l3)
        w4[0, k] = w0
        w4[1, k] = w1
        w4[2, k] = w2
        w4[3, k] = w3


@helper(fastmath=CONTRACT_ARCP)
def _observer_shadow_weights(dirs, px, py, pz, r, rc, sx, sy, sz, mu_s, bottom, top, cos_phi, profiles, counts,
                             cell, w_nu, w_tab, p_r, p_m):
    """For an observer in the Earth's shadow (:func:`.geometry.in_earth_shadow`), the azimuth weights of the two
    single-scattering tables of a block of rays (flat x, y, z triples ``dirs``; cells and linear weights of
    :func:`_observer_coords`) by the rule of :func:`_inscatter` (:func:`.sampling.shadow_nu_weights`): the texels'
    weights ``(1 - w) a`` and ``w b`` are written as their sum, folded into the phase factors ``p_r``, ``p_m``, and
    the share of the second, in ``w_tab[0]``, ``w_tab[1]``, so that the gather (:func:`_observer_gather`) is that of
    the lit sky. ``r``: the observer's radius, ``rc`` the same clamped to the atmosphere; ``mu_s`` the sun zenith
    cosine of the slices (at least the tables' limit); ``cos_phi`` the cosines of the texels' azimuths
    (:func:`.geometry.scattering_nu_azimuth`)."""
    inv_r = 1.0 / r
    n_nu = cos_phi.shape[0]
    for k in range(cell.shape[0]):
        vx = dirs[3 * k]
        vy = dirs[3 * k + 1]
        vz = dirs[3 * k + 2]
        n2 = vx * vx + vy * vy + vz * vz
        inv = 1.0 / math.sqrt(n2) if n2 > 0.0 and n2 < math.inf else 0.0
        mu = clamp((px * vx + py * vy + pz * vz) * (inv * inv_r), -1.0, 1.0)
        nu = clamp((vx * sx + vy * sy + vz * sz) * inv, -1.0, 1.0)
        i_n = cell[k] % n_nu
        h_q, h_0, h_1 = shadow_exit_altitudes_cos(rc, mu, mu_s, nu, cos_phi[i_n], cos_phi[i_n + 1], bottom, top)
        w = w_nu[k]
        for t in range(2):
            a, b = shadow_ratios_fast(h_q, h_0, h_1, profiles[t], counts[t])
            n0 = (1.0 - w) * a
            n1 = w * b
            total = n0 + n1
            w_tab[t, k] = n1 / total if total > 0.0 else w
            if t == 0:
                p_r[k] *= total
            else:
                p_m[k] *= total


@helper(fastmath=CONTRACT_ARCP)
def _observer_gather(slices, n_nu, cell, w_mu, w_tab, w4, off, p_r, p_m, p_l, out):
    """Interpolation of the observer slices (:func:`observer_slices` as (n_mu * n_nu, C + 1, 4)) for a block of
    rays from :func:`_observer_coords`, linear along mu; along nu the two single-scattering tables with the weights
    ``w_tab`` (2, >= m) of :func:`_observer_nu_weights` and the multiple scattering through its four azimuth texels
    (weights ``w4``, outer offsets ``off``: :func:`_observer_azimuth_weights`); phase factors applied: ``out`` (m, C).

    One channel (luminance) has its own loop: with the channel count known to be 1 the compiler turns the texel
    reads into SIMD gathers (gather 6.6 -> 4.7 ns per ray, two-texel reads); for C channels it leaves the loop
    scalar."""
    n_c = out.shape[1]
    if n_c == 1:
        for k in range(cell.shape[0]):
            a = cell[k]
            b = a + n_nu
            wm = w_mu[k]
            w00, w01, w10, w11 = bilinear_weights(wm, w_tab[0, k])
            v = p_r[k] * (w00 * slices[a, 0, 0] + w01 * slices[a + 1, 0, 0] + w10 * slices[b, 0, 0]
                          + w11 * slices[b + 1, 0, 0])
            w00, w01, w10, w11 = bilinear_weights(wm, w_tab[1, k])
            v += p_m[k] * (w00 * slices[a, 0, 1] + w01 * slices[a + 1, 0, 1] + w10 * slices[b, 0, 1]
                           + w11 * slices[b + 1, 0, 1])
            a0 = a + off[0, k]
            a3 = a + off[1, k]
            u = (w4[0, k] * ((1.0 - wm) * slices[a0, 0, 2] + wm * slices[a0 + n_nu, 0, 2])
                 + w4[1, k] * ((1.0 - wm) * slices[a, 0, 2] + wm * slices[b, 0, 2])
                 + w4[2, k] * ((1.0 - wm) * slices[a + 1, 0, 2] + wm * slices[b + 1, 0, 2])
                 + w4[3, k] * ((1.0 - wm) * slices[a3, 0, 2] + wm * slices[a3 + n_nu, 0, 2]))
            out[k, 0] = v + p_l[k] * u
        return
    for k in range(cell.shape[0]):
        wm = w_mu[k]
        a = cell[k]
        b = a + n_nu
        a0 = a + off[0, k]
        a3 = a + off[1, k]
        # the phase factors folded into each table's weights, held for every channel
        r00, r01, r10, r11 = bilinear_weights(wm, w_tab[0, k])
        pr = p_r[k]
        r00, r01, r10, r11 = pr * r00, pr * r01, pr * r10, pr * r11
        m00, m01, m10, m11 = bilinear_weights(wm, w_tab[1, k])
        pm = p_m[k]
        m00, m01, m10, m11 = pm * m00, pm * m01, pm * m10, pm * m11
        pl = p_l[k]
        u0, u1, u2, u3 = pl * w4[0, k], pl * w4[1, k], pl * w4[2, k], pl * w4[3, k]
        for c in range(n_c):
            out[k, c] = (r00 * slices[a, c, 0] + r01 * slices[a + 1, c, 0] + r10 * slices[b, c, 0]
                         + r11 * slices[b + 1, c, 0]
                         + m00 * slices[a, c, 1] + m01 * slices[a + 1, c, 1] + m10 * slices[b, c, 1]
                         + m11 * slices[b + 1, c, 1]
                         + u0 * ((1.0 - wm) * slices[a0, c, 2] + wm * slices[a0 + n_nu, c, 2])
                         + u1 * ((1.0 - wm) * slices[a, c, 2] + wm * slices[b, c, 2])
                         + u2 * ((1.0 - wm) * slices[a + 1, c, 2] + wm * slices[b + 1, c, 2])
                         + u3 * ((1.0 - wm) * slices[a3, c, 2] + wm * slices[a3 + n_nu, c, 2]))


@kernel
def observer_kernel(position, sun, slices, n_r, transmittance, irradiance, albedo, solar, projection, bottom, top,
                    mu_s_min, g, mie_kind, lobe, profiles, counts, alpha, include_ground, dirs, out, bad, start, stop):
    """:func:`sky_kernel`'s radiance (no shadows) for rays ``start..stop`` from one ``position`` inside the
    atmosphere with one ``sun`` direction, projected to C channels (``out`` (n_rays, C)); ``slices`` of
    :func:`observer_slices` from 4D tables of ``n_r`` radii.

    Inscattering from :func:`observer_slices` (in ``mu`` and ``nu``: the same values as the 4D lookup, or in
    twilight the single scattering computed at the observer's sun on the slices' finer azimuth axis); the
    ground term, a product of spectra (transmittance times irradiance), is formed per wavelength
    and then projected with ``projection`` (C, n_wavelengths). ``dirs`` need not be unit vectors; a zero,
    infinite or NaN one sets ``bad[q]`` (the caller raises). Rays go in blocks of :data:`OBSERVER_BLOCK` in
    passes: coordinates (vectorised), the ground half's ``mu`` cell for rays that meet the ground (only in blocks
    that have such rays or bad directions), the azimuth weights (vectorised; for an observer in the Earth's shadow,
    a test once per call, those of the single scattering then with the shadow factors of
    :func:`_observer_shadow_weights`), table reads, then for the rays that meet the ground the coordinates of the
    ground term (vectorised) and its spectrum, projected. ``mu_s_min``: the tables' sun limit; ``profiles``,
    ``counts``: the density profiles of :func:`.compute.density_profiles`.
    """
    n_l = transmittance.shape[2]
    n_c = out.shape[1]  # slices: n_c channels and the sums over wavelengths
    n_mu, n_nu = slices.shape[1], slices.shape[2]
    half = n_mu // 2
    flat = slices[0].reshape(n_mu * n_nu, slices.shape[3], 4)
    flat1 = slices[1].reshape(n_mu * n_nu, slices.shape[3], 4)
    t = np.empty(n_l)
    tmp = np.empty(n_l)
    e_sky = np.empty(n_l)
    e_sun = np.empty(n_l)
    ground = np.empty(n_l)
    cell = np.empty(OBSERVER_BLOCK, dtype=np.int64)
    cell1 = np.empty(OBSERVER_BLOCK, dtype=np.int64)
    kind = np.empty(OBSERVER_BLOCK, dtype=np.int64)
    w_mu = np.empty(OBSERVER_BLOCK)
    w_mu1 = np.empty(OBSERVER_BLOCK)
    upper = np.empty((OBSERVER_BLOCK, n_c))
    w_nu = np.empty(OBSERVER_BLOCK)
    w_tab = np.empty((2, OBSERVER_BLOCK))
    ends = np.empty((2, 2, OBSERVER_BLOCK), dtype=np.float32)
    w4 = np.empty((4, OBSERVER_BLOCK), dtype=np.float32)
    off = np.empty((2, OBSERVER_BLOCK), dtype=np.int64)
    ends4 = np.empty((4, OBSERVER_BLOCK), dtype=np.float32)
    nu_i = np.empty(OBSERVER_BLOCK, dtype=np.int64)
    p_r = np.empty(OBSERVER_BLOCK)
    p_m = np.empty(OBSERVER_BLOCK)
    p_l = np.empty(OBSERVER_BLOCK)
    g_idx = np.empty(OBSERVER_BLOCK, dtype=np.int64)
    g_v = np.empty((3, OBSERVER_BLOCK))
    g_mu = np.empty(OBSERVER_BLOCK)
    g_c = np.empty((9, OBSERVER_BLOCK))
    n_tr, n_tmu = transmittance.shape[0], transmittance.shape[1]
    n_er, n_emu = irradiance.shape[0], irradiance.shape[1]
    px, py, pz = position[0], position[1], position[2]
    sx, sy, sz = sun[0], sun[1], sun[2]
    r = math.sqrt(px * px + py * py + pz * pz)
    rc = clamp(r, bottom, top)
    mu_s = clamp((px * sx + py * sy + pz * sz) / r, -1.0, 1.0)
    rho, big_h, theta_h = horizon_constants(rc, bottom, top)
    two_rows = observer_two_rows(rc, bottom, top, n_r)
    mu_s_t = max(mu_s, mu_s_min)  # the sun of the slices (observer_slices)
    shadowed = in_earth_shadow(rc, mu_s_t, bottom)
    cos_phi = np.empty(n_nu)
    for i in range(n_nu):
        cos_phi[i] = math.cos(scattering_nu_azimuth(i, n_nu))
    flat_dirs = dirs.reshape(-1)
    for b0 in range(start, stop, OBSERVER_BLOCK):
        b1 = min(b0 + OBSERVER_BLOCK, stop)
        m = b1 - b0
        block = flat_dirs[3 * b0:3 * b1]
        special = _observer_coords(block, _unit_block(block), px, py, pz, r, rc, sx, sy, sz, mu_s, bottom, top, rho,
                                   big_h, theta_h, g, mie_kind, lobe, n_mu, n_nu, cell[:m], w_mu[:m], w_nu[:m],
                                   nu_i[:m], p_r[:m], p_m[:m], p_l[:m], kind[:m])
        if two_rows:
            _observer_row_cells(block, px, py, pz, r, bottom, top, n_r, n_mu, n_nu, cell[:m], w_mu[:m], cell1[:m],
                                w_mu1[:m])
        n_ground = 0
        for k in range(m if special else 0):
            if kind[k] == 2:
                # the ground half of the mu axis; the unit direction and mu kept for the ground term
                vx, vy, vz = block[3 * k], block[3 * k + 1], block[3 * k + 2]
                inv = 1.0 / math.sqrt(vx * vx + vy * vy + vz * vz)
                mu = clamp((px * vx + py * vy + pz * vz) * inv / r, -1.0, 1.0)
                i_mu, w_mu[k] = lerp_index(ground_mu_unit(rc, mu, bottom, rho) * (half - 1), 0, half - 1)
                cell[k] = i_mu * n_nu + cell[k] % n_nu
                cell1[k] = cell[k]  # both rows at the query's coordinate (sampling.r_mu_cell)
                w_mu1[k] = w_mu[k]
                g_idx[n_ground] = k
                g_v[0, n_ground] = vx * inv
                g_v[1, n_ground] = vy * inv
                g_v[2, n_ground] = vz * inv
                g_mu[n_ground] = mu
                n_ground += 1
            elif kind[k] == 0:
                bad[b0 + k] = True
        _observer_nu_weights(flat, flat1, two_rows, n_nu, n_c, cell[:m], w_mu[:m], cell1[:m], w_mu1[:m], w_nu[:m],
                             w_tab, ends)
        _observer_azimuth_weights(flat, flat1, two_rows, n_nu, n_c, cell[:m], nu_i[:m], w_mu[:m], cell1[:m],
                                  w_mu1[:m], w_nu[:m], w4, off, ends4)
        if shadowed:
            _observer_shadow_weights(block, px, py, pz, r, rc, sx, sy, sz, mu_s_t, bottom, top, cos_phi, profiles,
                                     counts, cell[:m], w_nu[:m], w_tab, p_r[:m], p_m[:m])
        _observer_gather(flat, n_nu, cell[:m], w_mu[:m], w_tab, w4, off, p_r[:m], p_m[:m], p_l[:m], out[b0:b1])
        if two_rows:
            _observer_gather(flat1, n_nu, cell1[:m], w_mu1[:m], w_tab, w4, off, p_r[:m], p_m[:m], p_l[:m],
                             upper[:m])
            for k in range(m):
                for ch in range(n_c):
                    out[b0 + k, ch] += upper[k, ch]
        if n_ground == 0 or not include_ground:
            continue
        _ground_coords_block(n_ground, g_v, g_mu, px, py, pz, sx, sy, sz, rc, bottom, top, alpha, n_tr, n_tmu, n_er,
                             n_emu, g_c)
        for j in range(n_ground):
            _ground_from_coords(transmittance, irradiance, albedo, solar, g_c[0, j], g_c[1, j], g_c[2, j],
                                g_c[3, j], g_c[4, j], g_c[5, j], g_c[6, j], g_c[7, j], g_c[8, j], t, tmp, e_sky, e_sun,
                                ground)
            q = b0 + g_idx[j]
            for ch in range(n_c):
                acc = 0.0
                for i in range(n_l):
                    acc += projection[ch, i] * ground[i]
                out[q, ch] += acc


@helper
def _slice_layers(l0, l1, w_r, w_g, i_s, w_s, projection, identity, two_rows, j, acc, out):
    """Table ``j`` (0 single Rayleigh, 1 single Mie, 2 multiple) of :func:`observer_slices` into ``out`` (2, n_mu,
    n_nu, C + 1, 4) from the table's two radius layers ``l0``, ``l1`` (n_mu, n_mu_s, n_nu, n_wavelengths) float32
    around the observer: the same sums in the same order as :func:`observer_slices` (each corner's weight rounded
    to float32 and multiplied in float32, as numpy does there, then summed in float64), so that the slices agree
    to the bit for an ``identity`` projection and to rounding for another; the ground half of the mu axis with its
    own radius weight ``w_g`` (:func:`.sampling.r_mu_s_cell`); with ``two_rows`` (:func:`observer_two_rows`) the
    rows' shares apart in ``out[0]`` and ``out[1]``. ``acc``: a buffer (n_wavelengths,)."""
    n_mu, _, n_nu, n_l = l0.shape
    n_c = projection.shape[0]
    mid = n_l // 2
    half = n_mu // 2
    for part in range(2 if two_rows else 1):
        for i in range(n_mu):
            w_row = w_g if i < half else w_r
            for q in range(n_nu):
                for k in range(n_l):
                    acc[k] = 0.0
                for a in range(2):
                    if two_rows and a != part:
                        continue
                    wa = w_row if a else 1.0 - w_row
                    layer = l1 if a else l0
                    for c in range(2):
                        wc = w_s if c else 1.0 - w_s
                        w = wa * wc
                        if w > 0.0:
                            wf = np.float32(w)
                            for k in range(n_l):
                                acc[k] += np.float64(wf * layer[i, i_s + c, q, k])
                if identity:
                    for k in range(n_c):
                        out[part, i, q, k, j] = acc[k]
                else:
                    for ch in range(n_c):
                        v = 0.0
                        for k in range(n_l):
                            v += projection[ch, k] * acc[k]
                        out[part, i, q, ch, j] = v
                out[part, i, q, n_c, j] = acc[mid]


@kernel
def observer_suns_kernel(position, r_slices, n_r, suns, mu_s, ray0, mie0, mult0, ray1, mie1, mult1, transmittance,
                         irradiance, albedo, solar, projection, identity, bottom, top, mu_s_min, cells, g, mie_kind,
                         lobe, profiles, counts, alpha, include_ground, dirs, out, bad, start, stop):
    """:func:`observer_kernel` for suns ``start..stop`` of ``suns`` (n, 3) (unit vectors; ``mu_s`` their zenith
    cosines at the observer, as :func:`observer_slices` takes them) seen from one ``position``: per sun the slices
    of :func:`observer_slices` (at the radius ``r_slices`` [m], clamped to the atmosphere, of tables with ``n_r``
    radii) from the scattering tables' two radius layers around the observer (``ray0``, ``mie0``, ``mult0`` and
    ``ray1``, ``mie1``, ``mult1``: (n_mu, n_mu_s, n_nu, n_wavelengths) float32), then the rays ``dirs`` into
    ``out[h]`` (n_suns, n_rays, C) and ``bad[h]``. One call for many suns: the loop over the suns (a year of
    hours) runs here, in parallel chunks, instead of one Python call and one slice per sun."""
    n_mu, n_s, n_nu, _ = ray0.shape
    n_c = projection.shape[0]
    slices = np.zeros((2, n_mu, n_nu, n_c + 1, 4))
    acc = np.empty(ray0.shape[3])
    n_rays = dirs.shape[0]
    two_rows = observer_two_rows(r_slices, bottom, top, n_r)
    for h in range(start, stop):
        slices[:] = 0.0
        m = mu_s[h]
        if m >= mu_s_min - MU_S_LIMIT_TOLERANCE:
            m = max(m, mu_s_min)
            _, w_r, i_s, w_s, w_g = r_mu_s_cell(r_slices, m, bottom, top, mu_s_min, n_r, n_s, cells)
            _slice_layers(ray0, ray1, w_r, w_g, i_s, w_s, projection, identity, two_rows, 0, acc, slices)
            _slice_layers(mie0, mie1, w_r, w_g, i_s, w_s, projection, identity, two_rows, 1, acc, slices)
            _slice_layers(mult0, mult1, w_r, w_g, i_s, w_s, projection, identity, two_rows, 2, acc, slices)
        observer_kernel(position, suns[h], slices, n_r, transmittance, irradiance, albedo, solar, projection,
                        bottom, top, mu_s_min, g, mie_kind, lobe, profiles, counts, alpha, include_ground, dirs, out[h],
                        bad[h], 0, n_rays)


@helper(fastmath=CONTRACT_ARCP)
def _inscatter_to_point(transmittance, ray, mie, mult, r, mu, mu_s, nu, d, hits, bottom, top, mu_s_min, cells, lobe,
                        p_r, p_m, p_m_spec, profiles, counts, c, t, c2, tmp):
    """``S|x - T(x, p) S|p`` for the point p at distance d along the ray into ``c``; leaves T(x, p) in ``t``."""
    _inscatter(ray, mie, mult, r, mu, mu_s, nu, hits, bottom, top, mu_s_min, cells, lobe, p_r, p_m, p_m_spec,
               profiles, counts, c)
    r_p, mu_p = point_along_ray(r, mu, d, bottom, top)
    mu_s_p = clamp((r * mu_s + d * nu) / r_p, -1.0, 1.0)
    _inscatter(ray, mie, mult, r_p, mu_p, mu_s_p, nu, hits, bottom, top, mu_s_min, cells, lobe, p_r, p_m, p_m_spec,
               profiles, counts, c2)
    transmittance_segment(transmittance, r, mu, d, hits, bottom, top, t, tmp)
    for k in range(c.shape[0]):
        c[k] = max(c[k] - t[k] * c2[k], 0.0)


@kernel
def aerial_kernel(cams, points, suns, shadow, transmittance, ray, mie, mult, bottom, top, mu_s_min, cells, g,
                  mie_kind, lobe, phase_mu, phase_values, profiles, counts, tr_out, in_out, start, stop):
    """Transmittance and inscattered radiance between cameras and points (Eqs. 16-17), rays ``start..stop``.

    Writes ``tr_out`` (initialised to 1) and ``in_out`` (initialised to 0), each (n_rays, n_wavelengths).
    ``shadow`` is the shadowed length [m] of each ray, moved to the point's end as in Eq. 17; ``profiles``,
    ``counts``: the density profiles of :func:`.compute.density_profiles` (the Earth's shadow, :func:`_inscatter`).
    """
    n_l = transmittance.shape[2]
    c = np.empty(n_l)
    t = np.empty(n_l)
    c2 = np.empty(n_l)
    tmp = np.empty(n_l)
    lo_c = np.empty(n_l)
    p_m_spec = np.empty(n_l if mie_kind == TABLE_PHASE else 0)
    for q in range(start, stop):
        dx = points[q, 0] - cams[q, 0]
        dy = points[q, 1] - cams[q, 1]
        dz = points[q, 2] - cams[q, 2]
        dist = math.sqrt(dx * dx + dy * dy + dz * dz)
        if dist <= 0.0:
            continue
        vx, vy, vz = dx / dist, dy / dist, dz / dist
        sx, sy, sz = suns[q, 0], suns[q, 1], suns[q, 2]
        px, py, pz, d_in, inside = _enter_atmosphere(cams[q, 0], cams[q, 1], cams[q, 2], vx, vy, vz, top)
        if not inside:
            continue
        d = dist - d_in
        if d <= 0.0:
            continue
        r = math.sqrt(px * px + py * py + pz * pz)
        rc = clamp(r, bottom, top)
        mu = clamp((px * vx + py * vy + pz * vz) / r, -1.0, 1.0)
        mu_s = clamp((px * sx + py * sy + pz * sz) / r, -1.0, 1.0)
        nu = clamp(vx * sx + vy * sy + vz * sz, -1.0, 1.0)
        hits = ray_hits_ground(rc, mu, bottom)
        transmittance_segment(transmittance, rc, mu, d, hits, bottom, top, t, tmp)
        for k in range(n_l):
            tr_out[q, k] = t[k]
        d_lit = max(d - shadow[q], 0.0)
        if d_lit <= 0.0:
            continue
        p_r = rayleigh_phase(nu)
        p_m = aerosol_phase(nu, g, mie_kind) if mie_kind != TABLE_PHASE else 0.0
        if p_m_spec.shape[0]:
            phase_table_values(phase_mu, phase_values, nu, p_m_spec)
        mu_h = -math.sqrt(max(1.0 - (bottom / rc) ** 2, 0.0))
        if abs(mu - mu_h) < HORIZON_EPSILON:
            # Blend the rays just above and below the horizon: the two halves of the table disagree there.
            mu_lo = mu_h - HORIZON_EPSILON
            mu_hi = mu_h + HORIZON_EPSILON
            _inscatter_to_point(transmittance, ray, mie, mult, rc, mu_lo, mu_s, nu, d_lit, True, bottom, top,
                                mu_s_min, cells, lobe, p_r, p_m, p_m_spec, profiles, counts, lo_c, t, c2, tmp)
            _inscatter_to_point(transmittance, ray, mie, mult, rc, mu_hi, mu_s, nu, d_lit, False, bottom, top,
                                mu_s_min, cells, lobe, p_r, p_m, p_m_spec, profiles, counts, c, t, c2, tmp)
            a = (mu - mu_lo) / (mu_hi - mu_lo)
            for k in range(n_l):
                c[k] = (1.0 - a) * lo_c[k] + a * c[k]
        else:
            _inscatter_to_point(transmittance, ray, mie, mult, rc, mu, mu_s, nu, d_lit, hits, bottom, top,
                                mu_s_min, cells, lobe, p_r, p_m, p_m_spec, profiles, counts, c, t, c2, tmp)
        for k in range(n_l):
            in_out[q, k] = c[k]


@kernel
def irradiance_kernel(points, normals, suns, transmittance, irradiance, solar, bottom, top, alpha, sun_out,
                      sky_out, start, stop):
    """Sun and sky irradiance [W m^-2 nm^-1] on surfaces at ``points`` with unit ``normals``.

    Sun: ``E_sun T_sun max(n.s, 0)`` with the planet's occlusion of the disc; sky: the table's horizontal
    irradiance times ``(1 + n.up) / 2`` (Eq. 14), each wavelength read with its own weight along the sun zenith
    (:func:`.sampling.irradiance_read`). Writes ``sun_out`` and ``sky_out`` (n, n_wavelengths).
    """
    n_l = transmittance.shape[2]
    t = np.empty(n_l)
    e = np.empty(n_l)
    for q in range(start, stop):
        px, py, pz = points[q, 0], points[q, 1], points[q, 2]
        r = math.sqrt(px * px + py * py + pz * pz)
        ux, uy, uz = px / r, py / r, pz / r
        sx, sy, sz = suns[q, 0], suns[q, 1], suns[q, 2]
        nx, ny, nz = normals[q, 0], normals[q, 1], normals[q, 2]
        rc = clamp(r, bottom, top)
        mu_s = clamp(ux * sx + uy * sy + uz * sz, -1.0, 1.0)
        transmittance_to_sun(transmittance, rc, mu_s, bottom, top, alpha, t)
        cos_n = max(nx * sx + ny * sy + nz * sz, 0.0)
        irradiance_lookup(irradiance, rc, mu_s, bottom, top, e)
        occl = 0.5 * (1.0 + nx * ux + ny * uy + nz * uz)
        for k in range(n_l):
            sun_out[q, k] = solar[k] * t[k] * cos_n
            sky_out[q, k] = e[k] * occl


@kernel
def sun_kernel(pos, suns, transmittance, bottom, top, alpha, out, start, stop):
    """Transmittance towards the sun (times the visible disc fraction) from each position into ``out``
    (n, n_wl), initialised to 1 by the caller."""
    n_l = transmittance.shape[2]
    t = np.empty(n_l)
    for q in range(start, stop):
        sx, sy, sz = suns[q, 0], suns[q, 1], suns[q, 2]
        px, py, pz = pos[q, 0], pos[q, 1], pos[q, 2]
        r0 = math.sqrt(px * px + py * py + pz * pz)
        if r0 > top:
            rmu = px * sx + py * sy + pz * sz
            # Blocked by the planet?
            disc_g = rmu * rmu - r0 * r0 + bottom * bottom
            if rmu < 0.0 and disc_g >= 0.0:
                for k in range(n_l):
                    out[q, k] = 0.0
                continue
        px, py, pz, _, inside = _enter_atmosphere(px, py, pz, sx, sy, sz, top)
        if not inside:
            continue
        r = math.sqrt(px * px + py * py + pz * pz)
        rc = clamp(r, bottom, top)
        mu_s = clamp((px * sx + py * sy + pz * sz) / r, -1.0, 1.0)
        transmittance_to_sun(transmittance, rc, mu_s, bottom, top, alpha, t)
        for k in range(n_l):
            out[q, k] = t[k]
