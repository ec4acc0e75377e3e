"""DISORT (disortpp) plane-parallel reference radiances for the precomputed-atmosphere tests.

Stamnes, Tsay, Wiscombe & Jayaweera (1988), DISORT, Appl. Opt. 27, 2502, doi:10.1364/AO.27.002502; the disortpp
binding of it. The atmosphere is cut into ``n_layers`` plane-parallel layers from the top of the atmosphere to
the ground; each layer's Rayleigh, aerosol-extinction, aerosol-scattering and ozone optical depths are the exact
integrals of the exponential (or tent) density profiles over it. The layer phase function is the scattering
weighted mix of the Rayleigh moments (chi_0 = 1, chi_2 = 1/10 for 3/(16 pi)(1 + nu^2)) and the Legendre moments
of the Cornette-Shanks phase (Bruneton & Neyret 2008, Eq. 4), computed by Gauss-Legendre quadrature with 4000
nodes, or those of a tabulated aerosol phase (its ``PhaseTable.legendre_moments``, exact for the table).
Delta-M scaling and an intensity correction keep the forward peak accurate: the radiances take DISORT's
correction with the exact phase function ([BurasDowlingEmde2011], DISORT 4's default: the TMS single scattering
of [NakajimaTanaka1988] with the phase tabulated, not summed from its moments, and a secondary-scattering
correction near the sun), given per layer as the scattering-weighted mix of the Rayleigh phase and the aerosol's
(the Cornette-Shanks formula, or the phase table's nodes, between which DISORT interpolates linearly in the
cosine as the table itself does).

disortpp applies an intensity correction only when ``flags.intensity_corr_buras`` is set (DISORT's
``intensity_correction``); ``flags.intensity_corr_nakajima`` alone (DISORT's ``old_intensity_correction``) only
chooses the older of the two and corrects nothing. Until 2026-12-02 this module set that flag alone: its
radiances were the delta-M solution, whose single scattering has the phase truncated to 32 Legendre terms
(coarse sea salt's tables were 9-15 % above it 10 deg from the sun; docs/aerosols.md). The Nakajima-Tanaka
correction summed from 400 moments is no cure for a diffraction peak either: sea salt's (OPAC sscm) phase rebuilt
from 400 moments is
+3 % at 10 deg, +34 % at 20 deg and -106 % at 60 deg from the sun (Gibbs oscillation; 2000 moments: within
0.13 %), hence the tabulated phase.

This is independent of the code under test: only the atmosphere's parameters (coefficients, scale heights,
albedo, g, a tabulated phase's values) are shared.

The DISORT problem itself (beam from the top onto a Lambertian ground, radiance looking up at the ground or the
upward flux at the top) is set up once, in :func:`solve_ground_radiance` and :func:`solve_upward_flux`, for
every DISORT comparison of the tests (the tables, the Monte Carlo reference). Also the table sizes of the
tables-vs-DISORT tests (:data:`TABLE_SIZES`).
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np

from quadrature import gauss_legendre

#: Table sizes of the tables-vs-DISORT tests: the default angular resolution (mu 128, mu_s 32, nu 8) on half the
#: radii and smaller 2D tables.
TABLE_SIZES = dict(transmittance_mu=128, transmittance_r=32, irradiance_mu_s=32, irradiance_r=8, scattering_r=16,
                   scattering_mu=128, scattering_mu_s=32, scattering_nu=8)


@cache
def cornette_shanks_moments(g: float, n_moments: int, n_nodes: int = 4000) -> np.ndarray:
    """Legendre moments chi_l = 2 pi integral p(mu) P_l(mu) dmu, l = 0..n_moments, of the Cornette-Shanks phase
    normalised to chi_0 = 1 on the same quadrature (computed once per (g, n_moments, n_nodes); read-only)."""
    x, w = gauss_legendre(n_nodes)
    k = 3.0 / (8.0 * math.pi) * (1.0 - g * g) / (2.0 + g * g)
    p = k * (1.0 + x * x) / (1.0 + g * g - 2.0 * g * x) ** 1.5
    # Legendre polynomials by the three-term recurrence.
    chi = np.empty(n_moments + 1)
    p_prev, p_cur = np.ones_like(x), x.copy()
    chi[0] = np.sum(w * p)
    if n_moments >= 1:
        chi[1] = np.sum(w * p * p_cur)
    for ell in range(1, n_moments):
        p_next = ((2 * ell + 1) * x * p_cur - ell * p_prev) / (ell + 1)
        p_prev, p_cur = p_cur, p_next
        chi[ell + 1] = np.sum(w * p * p_cur)
    chi /= chi[0]
    chi.setflags(write=False)
    return chi


def _layer_integral(profile, z_lo: np.ndarray, z_hi: np.ndarray, n_sub: int = 64) -> np.ndarray:
    """Integral of a DensityProfile's relative density over [z_lo, z_hi] [m] (Gauss-Legendre per layer)."""
    x, w = gauss_legendre(n_sub)
    arr = profile.as_array()
    mid = 0.5 * (z_lo + z_hi)[:, None]
    half = 0.5 * (z_hi - z_lo)[:, None]
    z = mid + half * x[None, :]
    rho = np.zeros_like(z)
    start = 0.0
    assigned = np.zeros(z.shape, dtype=bool)
    for i, (width, a, b, c, d) in enumerate(arr):
        last = i == arr.shape[0] - 1
        sel = ~assigned & ((z < start + width) | last)
        rho[sel] = np.maximum(a * np.exp(b * z[sel]) + c * z[sel] + d, 0.0)
        assigned |= sel
        start += width
    return np.sum(rho * w[None, :], axis=1) * half[:, 0]


#: Cosines at which a Cornette-Shanks phase is tabulated for DISORT's intensity correction: 0.02 deg steps in the
#: scattering angle (linear interpolation in the cosine between them is within 1.2e-6 of the formula for g = 0.8).
CORNETTE_SHANKS_MU = np.cos(np.radians(np.linspace(180.0, 0.0, 9001)))


def cornette_shanks_phase(g: float, mu: np.ndarray) -> np.ndarray:
    """The Cornette-Shanks phase function (Bruneton & Neyret 2008, Eq. 4) at cosines ``mu`` [sr^-1]."""
    k = 3.0 / (8.0 * math.pi) * (1.0 - g * g) / (2.0 + g * g)
    return k * (1.0 + mu * mu) / (1.0 + g * g - 2.0 * g * mu) ** 1.5


def mixed_phase(rayleigh_fraction: np.ndarray, mu: np.ndarray, particles: np.ndarray) -> np.ndarray:
    """Per layer the phase function normalised to a mean of 1 over the sphere, as DISORT's intensity correction
    reads it: ``f_R 3/4 (1 + mu^2) + (1 - f_R) 4 pi p(mu)`` with ``f_R`` (n_layers,) the Rayleigh share of the
    scattering and ``particles`` the particles' phase [sr^-1] at the cosines ``mu``; (n_layers, n_mu)."""
    f_r = np.asarray(rayleigh_fraction, dtype=float)[:, None]
    return f_r * 0.75 * (1.0 + mu * mu)[None, :] + (1.0 - f_r) * (4.0 * math.pi) * np.asarray(particles)[None, :]


def _column(params, wavelength: float, n_layers: int, n_moments: int):
    """The plane-parallel column of ``params`` at ``wavelength`` [nm]: layer optical depths, single-scattering
    albedos and Legendre moments (n_layers, n_moments + 1), from the top down; the ground albedo; the exact
    phase per layer for the intensity correction, ``(mu, values)`` (:func:`mixed_phase`; ``mu`` ascending)."""
    wl = [float(wavelength)]
    beta_r = float(params.rayleigh_scattering_at(wl)[0])
    beta_me = float(params.mie_extinction_at(wl)[0])
    beta_ms = float(params.mie_scattering_at(wl)[0])
    beta_o = float(params.ozone_absorption_at(wl)[0])
    edges = np.linspace(params.thickness, 0.0, n_layers + 1)  # from the top down
    z_hi, z_lo = edges[:-1], edges[1:]
    i_r = _layer_integral(params.rayleigh_density, z_lo, z_hi)
    i_m = _layer_integral(params.aerosol_component.density, z_lo, z_hi)
    i_o = _layer_integral(params.ozone_density, z_lo, z_hi)
    tau_r, tau_ms = beta_r * i_r, beta_ms * i_m
    tau = tau_r + beta_me * i_m + beta_o * i_o
    ssa = (tau_r + tau_ms) / tau
    analytic = params.aerosol_component.analytic_phase
    if analytic is not None and analytic.kind == "cornette-shanks":
        chi_m = cornette_shanks_moments(analytic.g, n_moments)
        mu = CORNETTE_SHANKS_MU
        p_m = cornette_shanks_phase(analytic.g, mu)
    else:  # a tabulated phase: the exact moments of its table (DISORT applies delta-M to them itself)
        table = params.aerosol_phase_table(wl)
        chi_m = table.legendre_moments(n_moments + 1)[0]
        mu = np.cos(np.asarray(table.angles))[::-1]
        p_m = np.ravel(table.evaluate(mu))
    chi_r = np.zeros(n_moments + 1)
    chi_r[0], chi_r[2] = 1.0, 0.1
    f_r = tau_r / (tau_r + tau_ms)
    moments = f_r[:, None] * chi_r[None, :] + (1.0 - f_r)[:, None] * chi_m[None, :]
    return tau, ssa, moments, float(np.mean(params.ground_albedo_at(wl))), (mu, mixed_phase(f_r, mu, p_m))


def disort_radiance(params, wavelength: float, sun_zenith: float, view_zenith, view_azimuth,
                    *, n_layers: int = 150, n_streams: int = 32, n_moments: int = 400) -> np.ndarray:
    """Downwelling radiance at the ground per unit solar irradiance [sr^-1] (plane-parallel DISORT).

    Parameters
    ----------
    params : AtmosphereParameters
    wavelength : float
        [nm].
    sun_zenith : float
        [rad].
    view_zenith : array_like
        View zenith angles [rad] (looking up, < pi/2).
    view_azimuth : array_like
        Azimuths of the views relative to the sun's azimuth [rad].

    Returns
    -------
    ndarray, shape (len(view_zenith), len(view_azimuth))
    """
    tau, ssa, moments, albedo, phase = _column(params, wavelength, n_layers, n_moments)
    return solve_ground_radiance(tau, ssa, moments, sun_zenith=sun_zenith, view_zenith=view_zenith,
                                 relative_azimuth=view_azimuth, ground_albedo=albedo, n_streams=n_streams,
                                 exact_phase=phase)


def disort_diffuse_irradiance(params, wavelength: float, sun_zenith: float, *, altitude: float = 0.0,
                              n_layers: int = 150, n_streams: int = 32, n_moments: int = 400) -> float:
    """Diffuse downward irradiance on a horizontal surface at ``altitude`` [m] above the ground (default: on it)
    per unit solar irradiance [-] (plane-parallel DISORT, fluxes only): DISORT's diffuse down-flux, which is total
    minus the direct beam without delta-M scaling, so the light of a forward peak is in it (Stamnes et al. 1988;
    DISORT's RFLDN), at the optical depth of the column above ``altitude`` (the layers above it, and the part of
    its own layer above it integrated from the density profiles as :func:`_column` integrates each layer: the
    layer is homogeneous in DISORT, so the level is placed by its optical depth). Layers and moments as
    :func:`disort_radiance`."""
    tau, ssa, moments, albedo, _ = _column(params, wavelength, n_layers, n_moments)
    disortpp, cfg, dtau, rayleigh, moments = _config(tau, ssa, moments, sun_zenith=sun_zenith,
                                                     ground_albedo=albedo, n_streams=n_streams, n_moments=None)
    cfg.flags.comp_only_fluxes = True
    cfg.num_user_tau = 1
    cfg.allocate()
    _fill(cfg, dtau, ssa, moments, rayleigh, sun_zenith, albedo)
    cfg.tau_user = [_optical_depth_above(params, wavelength, float(altitude), n_layers) if altitude > 0.0
                    else float(dtau.sum())]  # at the ground by default
    return float(disortpp.DisortSolver().solve(cfg).flux_down[0])


def _optical_depth_above(params, wavelength: float, altitude: float, n_layers: int) -> float:
    """The vertical optical depth [-] from the top of :func:`_column`'s layers down to ``altitude`` [m]: each
    layer's part above ``altitude`` integrated from the profiles (:func:`_layer_integral`), so the layers wholly
    above it sum to the column's own optical depths."""
    wl = [float(wavelength)]
    edges = np.linspace(params.thickness, 0.0, n_layers + 1)
    z_hi, z_lo = edges[:-1], edges[1:]
    keep = z_hi > altitude
    z_hi, z_lo = z_hi[keep], np.maximum(z_lo[keep], altitude)
    tau = (float(params.rayleigh_scattering_at(wl)[0]) * _layer_integral(params.rayleigh_density, z_lo, z_hi)
           + float(params.mie_extinction_at(wl)[0]) * _layer_integral(params.aerosol_component.density, z_lo, z_hi)
           + float(params.ozone_absorption_at(wl)[0]) * _layer_integral(params.ozone_density, z_lo, z_hi))
    return float(tau.sum())


def _config(delta_tau, single_scattering_albedo, phase_moments, *, sun_zenith: float, ground_albedo: float,
            n_streams: int, n_moments: int | None, nakajima: bool = False, exact_phase=None):
    """The DISORT problem of every comparison: plane-parallel layers listed from the top down, a unit beam flux
    from the top at ``sun_zenith`` [rad] (azimuth 0), a Lambertian ground of albedo ``ground_albedo``.
    ``phase_moments`` is (n_layers, n_moments + 1) Legendre moments per layer, or "rayleigh" (DISORT's own
    Rayleigh moments, then ``n_moments`` is required). The intensity correction (module docstring): with
    ``exact_phase`` ``(mu, values)`` (ascending cosines (n,), (n_layers, n) :func:`mixed_phase`) that of
    [BurasDowlingEmde2011]; else with ``nakajima`` that of [NakajimaTanaka1988] from the moments; else none (the
    phase is filled by :func:`_fill`)."""
    import disortpp

    dtau = np.asarray(delta_tau, dtype=float)
    rayleigh = isinstance(phase_moments, str)
    if rayleigh:
        assert phase_moments == "rayleigh" and n_moments is not None
    else:
        phase_moments = np.asarray(phase_moments, dtype=float)
        n_moments = phase_moments.shape[1] - 1
    cfg = disortpp.DisortConfig(dtau.size, n_streams, n_moments)
    cfg.flags.use_lambertian_surface = True
    cfg.flags.use_user_tau = True
    if exact_phase is not None or nakajima:
        cfg.flags.intensity_corr_buras = True  # disortpp's switch for any intensity correction
        cfg.flags.intensity_corr_nakajima = exact_phase is None
    if exact_phase is not None:
        cfg.num_phase_func_angles = int(np.asarray(exact_phase[0]).size)
    return disortpp, cfg, dtau, rayleigh, phase_moments


def _fill(cfg, dtau, single_scattering_albedo, phase_moments, rayleigh, sun_zenith, ground_albedo, exact_phase=None):
    if exact_phase is not None:
        mu, values = (np.asarray(a, dtype=float) for a in exact_phase)
        assert values.shape == (dtau.size, mu.size) and np.all(np.diff(mu) > 0)
        cfg.mu_phase_function = mu.tolist()
        cfg.phase_function = values.tolist()
    cfg.delta_tau = [float(t) for t in dtau]
    cfg.single_scat_albedo = [float(s) for s in np.asarray(single_scattering_albedo, dtype=float)]
    if rayleigh:
        cfg.set_rayleigh()
    else:
        cfg.phase_function_moments = [[float(c) for c in row] for row in phase_moments]
    cfg.bc.direct_beam_flux = 1.0
    cfg.bc.direct_beam_mu = math.cos(sun_zenith)
    cfg.bc.direct_beam_phi = 0.0
    cfg.bc.surface_albedo = float(ground_albedo)


def solve_ground_radiance(delta_tau, single_scattering_albedo, phase_moments, *, sun_zenith: float, view_zenith,
                          relative_azimuth, ground_albedo: float, n_streams: int = 32, n_moments: int | None = None,
                          nakajima: bool = True, exact_phase=None) -> np.ndarray:
    """Downwelling radiance at the ground per unit beam flux [sr^-1] looking up at ``view_zenith`` [rad]
    (< pi/2) and ``relative_azimuth`` [rad] from the sun's azimuth, shape (n_view, n_azimuth). Layers, phase
    moments, the boundary and the intensity correction (``exact_phase``, else ``nakajima``) as in
    :func:`_config`.
    """
    disortpp, cfg, dtau, rayleigh, moments = _config(delta_tau, single_scattering_albedo, phase_moments,
                                                     sun_zenith=sun_zenith, ground_albedo=ground_albedo,
                                                     n_streams=n_streams, n_moments=n_moments, nakajima=nakajima,
                                                     exact_phase=exact_phase)
    vz = np.atleast_1d(np.asarray(view_zenith, dtype=float))
    va = np.atleast_1d(np.asarray(relative_azimuth, dtype=float))
    mu = -np.cos(vz)  # downwelling: DISORT's negative cosines
    order = np.argsort(mu)
    cfg.flags.use_user_mu = True
    cfg.num_user_tau = 1
    cfg.num_user_mu = vz.size
    cfg.num_phi = va.size
    cfg.allocate()
    _fill(cfg, dtau, single_scattering_albedo, moments, rayleigh, sun_zenith, ground_albedo, exact_phase)
    cfg.tau_user = [float(dtau.sum())]  # at the ground
    cfg.mu_user = [float(m) for m in mu[order]]
    cfg.phi_user = [float(math.degrees(a)) for a in va]
    res = disortpp.DisortSolver().solve(cfg)
    out = np.empty((vz.size, va.size))
    for k, idx in enumerate(order):
        for j in range(va.size):
            out[idx, j] = res.intensities(k, 0, j)
    return out


def water_cloud_case(tau: float, rayleigh: bool, albedo: float, bottom_radius: float):
    """The water-cloud case of the DISORT validations (tests/test_montecarlo_clouds.py,
    benchmarks/validate_clouds.py): a ``CloudLayer`` from 1000 to 1500 m of optical depth ``tau`` at 550 nm (Mie
    droplets, effective radius 10 um, variance 0.1), alone or over Rayleigh air, no aerosol, no ozone, a Lambertian
    ground of ``albedo`` [-], the planet's radius ``bottom_radius`` [m] (huge for the plane-parallel limit), the
    top 60 km above it. Returns ``(layer, atmosphere)``."""
    from skyscatter.atmosphere import AtmosphereParameters
    from skyscatter.atmosphere.clouds import CloudLayer

    layer = CloudLayer(1000.0, 1500.0, float(tau), effective_radius=10e-6, effective_variance=0.1)
    kw = {} if rayleigh else dict(rayleigh_scattering=0.0)
    atm = AtmosphereParameters(bottom_radius=bottom_radius, top_radius=bottom_radius + 60000.0,
                               mie_angstrom_beta=0.0, ozone_column=0.0, ground_albedo=albedo, particles=(layer,), **kw)
    return layer, atm


def disort_cloud(atm, layer, wl, sun_zen, view_zen, view_azi, albedo, n_layers=100, n_streams=64,
                 single_scatter=False):
    """disortpp: Rayleigh (if any) and a cloud layer (``CloudLayer``: its extinction, albedo and the Legendre
    moments of its phase table, 400) over a Lambertian ground of ``albedo``; plane-parallel, 64 streams, delta-M and the
    intensity correction with the exact phase (its table; module docstring). Returns the downward radiance at the ground
    per unit solar irradiance [sr^-1], (n_view_zenith, n_view_azimuth), and the diffuse downward flux at the ground /
    (mu0 F0).

    ``single_scatter``: instead of disortpp's correction, add the TMS correction of [NakajimaTanaka1988] (their Eq.
    14-15) explicitly, the single-scattered radiance with the exact phase function (the cloud's table, Rayleigh's
    ``3/(16 pi)(1 + cos^2)``) over ``1 - f`` minus that with delta-M's truncated Legendre series, both attenuated
    through the delta-M scaled layers (``tau' = (1 - omega f) tau``, ``omega' = (1 - f) omega / (1 - omega f)``,
    ``f`` the layer's moment of order ``n_streams`` as DISORT takes it): a second, independent form of the same
    correction (benchmarks/cloudy_radiance_disort.py wrote its stored values with it)."""
    import disortpp

    n_mom = 400
    cloud_top = layer.top
    # layers: fine through the cloud (20 layers) and above/below it
    edges = np.unique(np.concatenate([np.linspace(atm.thickness, cloud_top, n_layers - 30 + 1),
                                      np.linspace(cloud_top, layer.base, 21), np.linspace(layer.base, 0.0, 11)]))[::-1]
    z_hi, z_lo = edges[:-1], edges[1:]
    beta_r = float(atm.rayleigh_scattering_at([wl])[0])
    tau_r = beta_r * _layer_integral(atm.rayleigh_density, z_lo, z_hi)
    sigma_c = float(layer.extinction_at([wl])[0])
    ssa_c = float(layer.single_scattering_albedo_at([wl])[0])
    overlap = np.clip(np.minimum(z_hi, layer.top) - np.maximum(z_lo, layer.base), 0.0, None)
    tau_c = sigma_c * overlap
    tau = tau_r + tau_c
    sca = tau_r + tau_c * ssa_c
    table = layer.phase_table([wl])
    chi_c = table.legendre_moments(n_mom + 1)[0]
    chi_r = np.zeros(n_mom + 1)
    chi_r[0], chi_r[2] = 1.0, 0.1
    with np.errstate(invalid="ignore", divide="ignore"):
        f_r = np.where(sca > 0, tau_r / sca, 1.0)
    moments = f_r[:, None] * chi_r[None, :] + (1.0 - f_r)[:, None] * chi_c[None, :]
    tau = np.maximum(tau, 1e-12)
    ssa = np.clip(sca / tau, 0.0, 1.0 - 1e-9)
    vz = np.asarray(view_zen, dtype=float)
    mu = -np.cos(vz)
    order = np.argsort(mu)
    cfg = disortpp.DisortConfig(tau.size, n_streams, n_mom)
    cfg.flags.use_user_mu = True
    cfg.flags.use_user_tau = True
    cfg.flags.use_lambertian_surface = True
    # the correction with the exact phase (module docstring), unless it is added explicitly below
    cfg.flags.intensity_corr_buras = not single_scatter
    mu_p = np.cos(np.asarray(table.angles))[::-1]
    cfg.num_phase_func_angles = mu_p.size
    cfg.num_user_tau = 1
    cfg.num_user_mu = vz.size
    cfg.num_phi = len(view_azi)
    cfg.allocate()
    cfg.mu_phase_function = mu_p.tolist()
    cfg.phase_function = mixed_phase(f_r, mu_p, np.ravel(table.evaluate(mu_p))).tolist()
    cfg.delta_tau = [float(t) for t in tau]
    cfg.single_scat_albedo = [float(s) for s in ssa]
    cfg.phase_function_moments = [[float(c) for c in row] for row in moments]
    cfg.tau_user = [float(tau.sum())]
    cfg.mu_user = [float(m) for m in mu[order]]
    cfg.phi_user = [float(math.degrees(a)) for a in view_azi]
    cfg.bc.direct_beam_flux = 1.0
    cfg.bc.direct_beam_mu = math.cos(sun_zen)
    cfg.bc.direct_beam_phi = 0.0
    cfg.bc.surface_albedo = float(albedo)
    res = disortpp.DisortSolver().solve(cfg)
    rad = np.empty((vz.size, len(view_azi)))
    for k, idx in enumerate(order):
        for j in range(len(view_azi)):
            rad[idx, j] = res.intensities(k, 0, j)
    if single_scatter:
        rad += _tms_correction(tau, ssa, moments, f_r, layer.phase_table([wl]), sun_zen, vz,
                               np.asarray(view_azi, dtype=float), n_streams)
    return rad, res.flux_down[0] / math.cos(sun_zen)


def _tms_correction(tau, ssa, moments, f_r, cloud_phase, sun_zen, view_zen, view_azi, n_streams):
    """Nakajima & Tanaka (1988) TMS correction of DISORT's delta-M radiance at the bottom of the layers looking up
    at ``view_zen`` (n_v,) x ``view_azi`` (n_a,) [rad] from the sun: (n_v, n_a) per unit solar irradiance
    [sr^-1]. Layers from the top down: ``tau``, ``ssa``, ``moments`` (n, m + 1), ``f_r`` the Rayleigh fraction of
    each layer's scattering; the cloud's exact phase from ``cloud_phase`` (a PhaseTable [sr^-1])."""
    mu0 = math.cos(sun_zen)
    mu = np.cos(view_zen)[:, None]  # the light travels down at this cosine
    cos_scat = mu * mu0 + np.sqrt(1 - mu ** 2) * math.sin(sun_zen) * np.cos(view_azi)[None, :]
    exact = (f_r[:, None, None] * 3.0 / (16.0 * math.pi) * (1.0 + cos_scat[None] ** 2)
             + (1.0 - f_r)[:, None, None] * cloud_phase.evaluate(cos_scat, 0)[None])  # (n, n_v, n_a) [sr^-1]
    f = moments[:, n_streams]
    ell = np.arange(n_streams)
    leg = np.empty((n_streams,) + cos_scat.shape)  # Legendre polynomials P_l(cos_scat), l < n_streams
    leg[0] = 1.0
    if n_streams > 1:
        leg[1] = cos_scat
    for n in range(1, n_streams - 1):
        leg[n + 1] = ((2 * n + 1) * cos_scat * leg[n] - n * leg[n - 1]) / (n + 1)
    chi_star = (moments[:, :n_streams] - f[:, None]) / (1.0 - f[:, None])
    truncated = np.einsum("il,l...->i...", chi_star * (2 * ell + 1), leg) / (4.0 * math.pi)
    tau_s = (1.0 - ssa * f) * tau
    ssa_s = (1.0 - f) * ssa / (1.0 - ssa * f)
    top = np.concatenate([[0.0], np.cumsum(tau_s)])
    total = top[-1]
    k = 1.0 / mu0 - 1.0 / mu  # (n_v, 1)
    a, b = top[:-1, None, None], top[1:, None, None]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        integral = np.where(np.abs(k) > 1e-9, (np.exp(-a * k) - np.exp(-b * k)) / np.where(k == 0, 1, k), b - a)
    atten = np.exp(-total / mu)[None] * integral / mu[None]
    return np.sum(ssa_s[:, None, None] * (exact / (1.0 - f[:, None, None]) - truncated) * atten, axis=0)


def solve_upward_flux(delta_tau, single_scattering_albedo, phase_moments, *, sun_zenith: float,
                      ground_albedo: float, n_streams: int = 32, n_moments: int | None = None) -> float:
    """Upward flux at the top of the layers per unit beam flux (fluxes only; layers, moments, boundary as in
    :func:`_config`)."""
    disortpp, cfg, dtau, rayleigh, moments = _config(delta_tau, single_scattering_albedo, phase_moments,
                                                     sun_zenith=sun_zenith, ground_albedo=ground_albedo,
                                                     n_streams=n_streams, n_moments=n_moments)
    cfg.flags.comp_only_fluxes = True
    cfg.num_user_tau = 1
    cfg.allocate()
    _fill(cfg, dtau, single_scattering_albedo, moments, rayleigh, sun_zenith, ground_albedo)
    cfg.tau_user = [0.0]  # at the top
    return float(disortpp.DisortSolver().solve(cfg).flux_up[0])


def sphericity_allowance(params, sun_zenith: float, view_zenith: np.ndarray) -> np.ndarray:
    """The first-order plane-parallel vs spherical difference bound (tests/test_precomputed_disort.py's module
    docstring) of ``params`` (AtmosphereParameters) at ``sun_zenith`` [rad] and ``view_zenith`` [rad] (array) [-]."""
    wl = [550.0]
    r = params.bottom_radius
    layers = ((8000.0, params.rayleigh_scattering_at(wl)[0] * 8000.0),
              (1200.0, params.mie_extinction_at(wl)[0] * 1200.0))
    t2s = math.tan(sun_zenith) ** 2
    t2v = np.tan(view_zenith) ** 2
    out = 8000.0 / r * t2v
    for h, tau in layers:
        out = out + tau * h / r * (t2s / math.cos(sun_zenith) + t2v / np.cos(view_zenith))
    return out
