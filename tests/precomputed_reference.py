"""Independent brute-force reference for the precomputed atmosphere tests (plain numpy, no tables).

A helper module (not a test module): tests/test_precomputed_reference.py checks it against closed forms.

Everything here integrates the radiative transfer integrals of Bruneton & Neyret (2008) directly along each
ray with fine Gauss-Legendre quadrature: optical depths (Eq. 5), transmittance, and single scattering
(Eqs. 9, 11 with L0). It shares no code with :mod:`skyscatter.precomputed` beyond the parameter object.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from quadrature import gauss_legendre
from skyscatter.precomputed import AtmosphereParameters, PrecomputedAtmosphere

#: Table sizes of the shared test atmosphere (an eighth of the default 4D table).
SMALL_SIZES = dict(transmittance_mu=128, transmittance_r=32, irradiance_mu_s=32, irradiance_r=8, scattering_r=16,
                   scattering_mu=64, scattering_mu_s=32, scattering_nu=8)


@cache
def small_earth(orders: int = 4) -> PrecomputedAtmosphere:
    """Earth-default tables at SMALL_SIZES and the 3 wavelengths of the seeds' check values (680, 550, 440 nm),
    computed once per test session (in memory only)."""
    return PrecomputedAtmosphere.compute(AtmosphereParameters(), orders=orders, sizes=SMALL_SIZES, progress=False,
                                         tables="rgb")


def ray_end(r: float, mu: float, params: AtmosphereParameters) -> tuple[float, bool]:
    """Distance to the end of the ray (ground or top) and whether it meets the ground."""
    rb, rt = params.bottom_radius, params.top_radius
    disc_g = r * r * (mu * mu - 1) + rb * rb
    if mu < 0 and disc_g >= 0:
        return -r * mu - np.sqrt(disc_g), True
    return -r * mu + np.sqrt(r * r * (mu * mu - 1) + rt * rt), False


def _gauss(n: int, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    x, w = gauss_legendre(n)
    return 0.5 * (b - a) * x + 0.5 * (b + a), 0.5 * (b - a) * w


def extinction(h: np.ndarray, params: AtmosphereParameters, wl: np.ndarray) -> np.ndarray:
    """Extinction coefficient [m^-1] at altitudes h, shape h.shape + (n_wl,)."""
    h = np.asarray(h, dtype=float)[..., None]
    return (params.rayleigh_density(h) * params.rayleigh_scattering_at(wl)
            + params.aerosol_component.density(h) * params.mie_extinction_at(wl)
            + params.ozone_density(h) * params.ozone_absorption_at(wl))


def optical_depth(r: np.ndarray, mu: np.ndarray, d: np.ndarray, params: AtmosphereParameters, wl: np.ndarray,
                  n: int = 400) -> np.ndarray:
    """Optical depth from (r, mu) over a length d, for arrays of rays (...,) -> (..., n_wl).

    The segment is split in 8 pieces of n/8 Gauss-Legendre points each.
    """
    r, mu, d = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (r, mu, d)))
    out = np.zeros((*r.shape, np.size(wl)))
    pieces = 8
    x, w = gauss_legendre(n // pieces)
    for k in range(pieces):
        a = d * k / pieces
        b = d * (k + 1) / pieces
        t = 0.5 * (b - a)[..., None] * x + 0.5 * (b + a)[..., None]
        ww = 0.5 * (b - a)[..., None] * w
        rr = np.sqrt(t * t + 2 * r[..., None] * mu[..., None] * t + r[..., None] ** 2)
        out += np.einsum("...i,...il->...l", ww, extinction(rr - params.bottom_radius, params, wl))
    return out


def transmittance(r: float, mu: float, params: AtmosphereParameters, wl: np.ndarray) -> np.ndarray:
    """Transmittance from (r, mu) to the ground or the top, (n_wl,)."""
    d, _ = ray_end(r, mu, params)
    return np.exp(-optical_depth(np.array(r), np.array(mu), np.array(d), params, wl))


def _cs_phase(nu: float, g: float) -> float:
    return 3 / (8 * np.pi) * (1 - g * g) * (1 + nu * nu) / ((2 + g * g) * (1 + g * g - 2 * g * nu) ** 1.5)


def single_scattering_integrals(r: float, mu: float, mu_s: float, nu: float, params: AtmosphereParameters,
                                wl: np.ndarray, n: int = 800, pieces: int = 24,
                                first: float = 1e-4) -> tuple[np.ndarray, np.ndarray]:
    """``integral rho_i(y) T(x, y) T_sun(y) dy`` for Rayleigh and the aerosol (i = R, M) along the ray from
    (r, mu), the sun at (mu_s, nu): what the single-scattering tables hold per unit solar irradiance and scattering
    coefficient, (n_wl,) each [m]. Point sun; the view and sun optical depths integrated along each path.

    Gauss-Legendre on ``pieces`` pieces growing geometrically from ``first`` of the ray's length (dense near the
    start, where the aerosols are), ``n`` points in all."""
    d_end, _ = ray_end(r, mu, params)
    edges = np.concatenate([[0.0], d_end * np.geomspace(first, 1.0, pieces)])
    ts, ws = [], []
    for a, b in zip(edges[:-1], edges[1:], strict=False):
        t, w = _gauss(max(n // pieces, 8), a, b)
        ts.append(t)
        ws.append(w)
    t = np.concatenate(ts)
    w = np.concatenate(ws)
    ry = np.sqrt(t * t + 2 * r * mu * t + r * r)
    mu_s_y = np.clip((r * mu_s + t * nu) / ry, -1, 1)
    tau_view = optical_depth(np.full_like(t, r), np.full_like(t, mu), t, params, wl, n=160)
    d_sun = np.array([ray_end(a, b, params)[0] for a, b in zip(ry, mu_s_y, strict=False)])
    blocked = np.array([ray_end(a, b, params)[1] for a, b in zip(ry, mu_s_y, strict=False)])
    tau_sun = optical_depth(ry, mu_s_y, d_sun, params, wl, n=160)
    tr = np.exp(-tau_view - tau_sun) * (~blocked)[:, None]
    h = ry - params.bottom_radius
    ray = (params.rayleigh_density(h)[:, None] * tr * w[:, None]).sum(0)
    mie = (params.aerosol_component.density(h)[:, None] * tr * w[:, None]).sum(0)
    return ray, mie


def single_scattering(r: float, mu: float, mu_s: float, nu: float, params: AtmosphereParameters, wl: np.ndarray,
                      n: int = 800) -> np.ndarray:
    """Singly scattered radiance [W m^-2 sr^-1 nm^-1] seen from (r, mu) with the sun at (mu_s, nu).

    The sun is a point source (the visible-disc fraction is ignored; tests avoid the horizon of the sun).
    """
    ray, mie = single_scattering_integrals(r, mu, mu_s, nu, params, wl, n)
    ray = ray * params.rayleigh_scattering_at(wl)
    mie = mie * params.mie_scattering_at(wl)
    p_r = 3 / (16 * np.pi) * (1 + nu * nu)
    return params.solar_irradiance_at(wl) * (ray * p_r + mie * aerosol_phase(nu, params, wl))


def aerosol_phase(nu: float, params: AtmosphereParameters, wl: np.ndarray) -> np.ndarray:
    """The aerosol phase [sr^-1] at ``nu``: Cornette-Shanks written out here, or the numpy interpolant of the
    aerosol's phase table (:meth:`PhaseTable.evaluate`) for a tabulated one, (n_wl,) or scalar."""
    analytic = params.aerosol_component.analytic_phase
    if analytic is not None and analytic.kind == "cornette-shanks":
        return _cs_phase(nu, analytic.g)
    return params.aerosol_phase_table(wl).evaluate(nu)
