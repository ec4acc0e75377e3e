"""DISORT (disortpp) plane-parallel reference radiances for the precomputed-atmosphere tests.

Stamnes, Tsay, Wiscombe & Jayaweera (1988), DISORT, Appl. Opt. 27, 2502, doi:10.1364/AO.27.002502; the disortpp
binding of it. The atmosphere is cut into ``n_layers`` plane-parallel layers from the top of the atmosphere to
the ground; each layer's Rayleigh, aerosol-extinction, aerosol-scattering and ozone optical depths are the exact
integrals of the exponential (or tent) density profiles over it. The layer phase function is the scattering
weighted mix of the Rayleigh moments (chi_0 = 1, chi_2 = 1/10 for 3/(16 pi)(1 + nu^2)) and the Legendre moments
of the Cornette-Shanks phase (Bruneton & Neyret 2008, Eq. 4), computed by Gauss-Legendre quadrature with 4000
nodes, or those of a tabulated aerosol phase (its ``PhaseTable.legendre_moments``, exact for the table).
Delta-M scaling and the Nakajima-Tanaka intensity correction (DISORT's defaults with many moments) keep
the forward peak accurate.

This is independent of the code under test: only the atmosphere's parameters (coefficients, scale heights,
albedo, g) are shared.
"""

from __future__ import annotations

import math

import numpy as np


def cornette_shanks_moments(g: float, n_moments: int, n_nodes: int = 4000) -> np.ndarray:
    """Legendre moments chi_l = 2 pi integral p(mu) P_l(mu) dmu, l = 0..n_moments, of the Cornette-Shanks phase
    normalised to chi_0 = 1 on the same quadrature."""
    x, w = np.polynomial.legendre.leggauss(n_nodes)
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
    return chi / chi[0]


def _layer_integral(profile, z_lo: np.ndarray, z_hi: np.ndarray, n_sub: int = 64) -> np.ndarray:
    """Integral of a DensityProfile's relative density over [z_lo, z_hi] [m] (Gauss-Legendre per layer)."""
    x, w = np.polynomial.legendre.leggauss(n_sub)
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
    import disortpp

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
    else:  # a tabulated phase: the exact moments of its table (DISORT applies delta-M to them itself)
        chi_m = params.aerosol_phase_table(wl).legendre_moments(n_moments + 1)[0]
    chi_r = np.zeros(n_moments + 1)
    chi_r[0], chi_r[2] = 1.0, 0.1
    f_r = tau_r / (tau_r + tau_ms)
    moments = f_r[:, None] * chi_r[None, :] + (1.0 - f_r)[:, None] * chi_m[None, :]

    vz = np.atleast_1d(np.asarray(view_zenith, dtype=float))
    va = np.atleast_1d(np.asarray(view_azimuth, dtype=float))
    mu = -np.cos(vz)
    order = np.argsort(mu)
    cfg = disortpp.DisortConfig(n_layers, n_streams, n_moments)
    cfg.flags.use_user_mu = True
    cfg.flags.use_user_tau = True
    cfg.flags.use_lambertian_surface = True
    cfg.flags.intensity_corr_nakajima = True
    cfg.num_user_tau = 1
    cfg.num_user_mu = vz.size
    cfg.num_phi = va.size
    cfg.allocate()
    cfg.delta_tau = [float(t) for t in tau]
    cfg.single_scat_albedo = [float(s) for s in ssa]
    cfg.phase_function_moments = [[float(c) for c in row] for row in moments]
    cfg.tau_user = [float(tau.sum())]
    cfg.mu_user = [float(m) for m in mu[order]]
    cfg.phi_user = [float(math.degrees(a)) for a in va]
    cfg.bc.direct_beam_flux = 1.0
    cfg.bc.direct_beam_mu = math.cos(sun_zenith)
    cfg.bc.direct_beam_phi = 0.0
    cfg.bc.surface_albedo = float(np.mean(params.ground_albedo_at(wl)))
    res = disortpp.DisortSolver().solve(cfg)
    out = np.empty((vz.size, va.size))
    for k, idx in enumerate(order):
        for j in range(va.size):
            out[idx, j] = res.intensities(k, 0, j)
    return out


def disort_cloud(atm, layer, wl, sun_zen, view_zen, view_azi, albedo, n_layers=100, n_streams=64):
    """disortpp: Rayleigh (if any) and a cloud layer (``CloudLayer``: its extinction, albedo and the Legendre
    moments of its phase table, 400) over a Lambertian ground of ``albedo``; plane-parallel, 64 streams, delta-M
    and the Nakajima-Tanaka correction. Returns the downward radiance at the ground per unit solar irradiance
    [sr^-1], (n_view_zenith, n_view_azimuth), and the diffuse downward flux at the ground / (mu0 F0)."""
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
    chi_c = layer.phase_table([wl]).legendre_moments(n_mom + 1)[0]
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
    cfg.flags.intensity_corr_nakajima = True
    cfg.num_user_tau = 1
    cfg.num_user_mu = vz.size
    cfg.num_phi = len(view_azi)
    cfg.allocate()
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
    return rad, res.flux_down[0] / math.cos(sun_zen)
