"""From radiance at the table wavelengths to spectra at any wavelength and to CIE XYZ.

The tables hold spectral radiance at wavelengths ``lambda_k``. In both modes below the radiance divided by the
solar irradiance at the top of the atmosphere, ``rho(lambda) = L(lambda) / E_sun(lambda)``, is what is
interpolated: it is a smooth function of wavelength (scattering efficiency times transmittance), while the
solar spectrum is not (Fraunhofer lines, a steep blue edge). ``E_sun`` is the 10-nm box-filtered solar
spectrum used for the tables (:meth:`AtmosphereParameters.solar_irradiance_at`). Spectra are
``E_sun(lambda) rho(lambda)``; XYZ is their integral with the CIE 1931 observer on a 1 nm grid
(``683 integral xbar L dlambda``, trapezoid) over 360-830 nm, or over the table range in the spectral mode.
Every rule is linear in the samples, so XYZ is a 3 x n matrix (:func:`xyz_matrix`), the kind of "radiance to
luminance" coefficients Bruneton's 2017 rewrite precomputes, derived here from a stated spectral model rather
than a fit.

* **Spectral mode** (15 or more wavelengths; the default tables, :data:`.sizes.DEFAULT_TABLE_WAVELENGTHS`):
  ``rho`` is interpolated linearly in ``lambda`` between neighbouring table wavelengths and is **zero outside
  the table range** ``[min lambda_k, max lambda_k]``: no light is invented beyond the computed wavelengths,
  and :meth:`ColourConversion.resample` returns exactly the table value at a table wavelength. The default
  tables span 400-700 nm every 20 nm; what the observer would see outside that range is within the error
  bounds measured there.
  Measured against the observer integral of 41 wavelengths (380-780 nm, 10 nm) of the same atmosphere:
  ``benchmarks/bruneton_colour_error.py`` and ``docs/bruneton.md``.
* **Few wavelengths** (e.g. the 3-wavelength mode, :data:`.sizes.RGB_TABLE_WAVELENGTHS`): both single
  scattering and transmission depend on wavelength mostly through the Rayleigh coefficient
  ``beta_R ~ lambda^-4``, so ``rho`` is modelled as a polynomial in ``x = (lambda / 550 nm)^-4`` through the
  samples: with 3 wavelengths the quadratic through the three ``(x_k, rho_k)`` (a second-order expansion in the
  Rayleigh optical depth), with 1 or 2 a constant or a line; with 4 to 14 wavelengths ``rho`` is interpolated
  linearly in ``x`` and held constant beyond the ends, over the whole 360-830 nm. This misses ozone's Chappuis
  band, which carves the middle of twilight spectra: the 3-wavelength twilight zenith comes out magenta
  where the spectral mode gives blue (``docs/bruneton.md`` has the measured error by sun elevation).
* **Guard against negative lobes** (few-wavelength mode). Near a low or set sun ``rho`` falls steeply towards
  the blue, and the quadratic through three samples can dip below zero between or beyond them (it gave negative
  Z and an invented violet peak at sunset). The piecewise-linear interpolant in ``x`` held constant beyond the end
  samples is a convex combination of the samples and so never negative. Each sample triple uses the blend
  ``(1 - t) quadratic + t linear`` with ``t = min(t0 (1 + 2 t0), 1)``, where ``t0 = max(-p / (l - p))`` over the
  wavelengths (360-830 nm, every 5 nm) where the quadratic ``p`` is negative (``l`` the linear rule there,
  ``l - p > 0`` wherever ``p < 0``) is the least weight that keeps the blend non-negative. ``t`` is 0 where the
  quadratic is non-negative, moves continuously with the samples, and reaches the linear rule alone when the
  negative lobe is deep: an all-or-nothing switch between the rules made 13-26 % jumps in the sky's luminance
  between directions 0.01 deg apart, 1-4 deg above the horizon at low sun (seams; docs/bruneton.md), while the least
  weight ``t0`` alone keeps the quadratic's rise beyond the 440 nm sample (a sunset triple then has
  ``rho(360 nm)`` 1400 times ``rho(440 nm)``: the invented violet). ``t0 (1 + 2 t0)`` lies between ``t0`` and ``2 t0``
  (both reach 1 at ``t0 = 0.5``): every triple whose quadratic is negative gets a blend that stays
  non-negative with margin, the linear rule at sunset, and at the lobe's onset the weight rises with the slope of
  ``t0`` itself, not twice it (with ``2 t0`` the ramp stepped the luminance 1.23 % between view elevations 0.01 deg
  apart where a lobe began 0.7 deg above the horizon opposite a sun on the horizon; 2026-12-04). Both rules are
  linear, so the blend costs two small matrix products and a maximum per sample (:class:`ColourConversion`).

Reference: [Bruneton2008].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..spectral import cie_cmfs, integration_weights
from ..spectral.colorimetry import LUMINOUS_EFFICACY
from .parameters import AtmosphereParameters

__all__ = ["SPECTRAL_MODE_MIN_WAVELENGTHS", "ColourConversion", "reconstruction_matrix", "xyz_matrix"]

#: From this many wavelengths on, XYZ is integrated directly from the samples.
SPECTRAL_MODE_MIN_WAVELENGTHS = 15
#: The 1 nm grid [nm] over the CIE observer's range on which spectra are rebuilt and integrated.
FINE_GRID = np.arange(360.0, 830.0 + 0.5, 1.0)


def _hat_basis(nodes: NDArray[np.float64], x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Piecewise-linear interpolation weights (len(x), len(nodes)) on increasing ``nodes``; constant beyond."""
    n = nodes.size
    out = np.zeros((x.size, n))
    if n == 1:
        out[:, 0] = 1.0
        return out
    eye = np.eye(n)
    for k in range(n):
        out[:, k] = np.interp(x, nodes, eye[k])
    return out


def _lagrange_basis(nodes: NDArray[np.float64], x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Lagrange polynomial weights (len(x), len(nodes)) through all ``nodes`` (degree len(nodes) - 1)."""
    out = np.ones((x.size, nodes.size))
    for k in range(nodes.size):
        for j in range(nodes.size):
            if j != k:
                out[:, k] *= (x - nodes[j]) / (nodes[k] - nodes[j])
    return out


def reconstruction_matrix(table_wavelengths: ArrayLike, wavelengths: ArrayLike,
                          atmosphere: AtmosphereParameters) -> NDArray[np.float64]:
    """Matrix (n_out, n_table) turning radiance at ``table_wavelengths`` into radiance at ``wavelengths`` [nm].

    ``L(lambda) = E_sun(lambda) * rho(lambda)`` with ``rho`` interpolating ``L_k / E_sun(lambda_k)`` (module
    docstring): in the spectral mode (15 or more table wavelengths) linearly in ``lambda`` and zero outside the
    table range; otherwise the polynomial (up to 3 samples) or piecewise-linear (4 to 14) interpolant in
    ``x = (lambda / 550 nm)^-4``. Not clamped: apply ``max(., 0)`` to spectra shown to users (only the
    3-sample polynomial can go negative).
    """
    tw = np.asarray(table_wavelengths, dtype=float)
    if tw.size >= SPECTRAL_MODE_MIN_WAVELENGTHS:
        return _spectral_reconstruction(tw, np.asarray(wavelengths, dtype=float), atmosphere)
    return _reconstruction(tw, wavelengths, atmosphere, piecewise_linear=False)


def _solar_ratio(e_out: NDArray[np.float64], basis: NDArray[np.float64],
                 e_tab: NDArray[np.float64]) -> NDArray[np.float64]:
    """``E_sun(lambda) * basis / E_sun(lambda_k)``: the interpolation of ``rho`` turned back into radiance."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(e_tab > 0, 1.0 / e_tab, 0.0)
    return e_out[:, None] * basis * inv[None, :]


def _spectral_reconstruction(tw: NDArray[np.float64], wl: NDArray[np.float64],
                             atmosphere: AtmosphereParameters) -> NDArray[np.float64]:
    """Spectral mode: ``rho`` linear in ``lambda`` between table wavelengths, zero outside their range."""
    order = np.argsort(tw)
    flat = wl.ravel()
    basis = np.zeros((flat.size, tw.size))
    basis[:, order] = _hat_basis(tw[order], flat)
    basis[(flat < tw.min()) | (flat > tw.max())] = 0.0
    inside = basis.any(axis=1)
    e_out = np.zeros(flat.size)
    if np.any(inside):  # the solar spectrum is only needed (and may only be tabulated) inside the range
        e_out[inside] = atmosphere.solar_irradiance_at(flat[inside])
    return _solar_ratio(e_out, basis, atmosphere.solar_irradiance_at(tw))


def _reconstruction(table_wavelengths: ArrayLike, wavelengths: ArrayLike, atmosphere: AtmosphereParameters, *,
                    piecewise_linear: bool) -> NDArray[np.float64]:
    tw = np.asarray(table_wavelengths, dtype=float)
    wl = np.asarray(wavelengths, dtype=float)
    # x = lambda^-4 decreases with lambda: interpolate on the reversed (increasing) node order.
    order = np.argsort(-tw)
    x_nodes = (tw[order] / 550.0) ** -4
    x = (wl / 550.0) ** -4
    basis = np.zeros((wl.size, tw.size))
    polynomial = tw.size <= 3 and not piecewise_linear
    basis[:, order] = _lagrange_basis(x_nodes, x) if polynomial else _hat_basis(x_nodes, x)
    return _solar_ratio(atmosphere.solar_irradiance_at(wl), basis, atmosphere.solar_irradiance_at(tw))


def xyz_matrix(table_wavelengths: ArrayLike, atmosphere: AtmosphereParameters) -> NDArray[np.float64]:
    """Matrix (3, n_table): ``xyz = M @ L`` gives CIE 1931 XYZ [cd m^-2] of radiance at the table wavelengths.

    The spectrum of :func:`reconstruction_matrix` (both modes) integrated with the CIE 1931 observer on a 1 nm
    grid (trapezoid) over 360-830 nm, or in the spectral mode over the table range, where the spectrum is not
    zero (the grid then also holds the range's ends, so the step to zero outside adds nothing).
    """
    tw = np.asarray(table_wavelengths, dtype=float)
    if tw.size >= SPECTRAL_MODE_MIN_WAVELENGTHS:
        lo, hi = tw.min(), tw.max()
        grid = np.unique(np.concatenate([[lo, hi], FINE_GRID[(FINE_GRID > lo) & (FINE_GRID < hi)]]))
        return _observer_matrix(grid).T @ reconstruction_matrix(tw, grid, atmosphere)
    return _observer_matrix(FINE_GRID).T @ reconstruction_matrix(tw, FINE_GRID, atmosphere)


def _observer_matrix(grid: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n_grid, 3): ``683 xbar(lambda) dlambda`` trapezoid weights on ``grid`` [nm] [lm W^-1 nm]."""
    return cie_cmfs(grid) * integration_weights(grid)[:, None] * LUMINOUS_EFFICACY


class ColourConversion:
    """Table radiance (..., n_table) to XYZ or to spectra, with the negative-lobe guard of the module docstring.

    Parameters
    ----------
    table_wavelengths : array_like
        Wavelengths of the tables [nm].
    atmosphere : AtmosphereParameters
        Gives the solar spectrum that ``rho = L / E_sun`` is interpolated against.
    """

    def __init__(self, table_wavelengths: ArrayLike, atmosphere: AtmosphereParameters) -> None:
        self.table_wavelengths = np.asarray(table_wavelengths, dtype=float)
        self.atmosphere = atmosphere
        tw = self.table_wavelengths
        self.spectral = tw.size >= SPECTRAL_MODE_MIN_WAVELENGTHS
        self.guarded = 2 <= tw.size <= 3
        self.xyz_polynomial = xyz_matrix(tw, atmosphere)
        if self.guarded:
            linear = _reconstruction(tw, FINE_GRID, atmosphere, piecewise_linear=True)
            self.xyz_linear = _observer_matrix(FINE_GRID).T @ linear
            # Where the blend is kept non-negative: every 5 nm over the observer's range.
            self._check_polynomial = reconstruction_matrix(tw, FINE_GRID[::5], atmosphere)
            self._check_linear = _reconstruction(tw, FINE_GRID[::5], atmosphere, piecewise_linear=True)

    def linear_weight(self, radiance: ArrayLike) -> NDArray[np.float64]:
        """Weight ``t`` (...,) of the piecewise-linear rule in the blend of the module docstring: ``t0 (1 + 2 t0)``
        of the least weight ``t0`` that keeps ``(1 - t) quadratic + t linear`` non-negative on the 5 nm check grid,
        at most 1 (0 where the quadratic is non-negative; always 0 in the spectral mode)."""
        rad = np.asarray(radiance, dtype=float)
        if not self.guarded:
            return np.zeros(rad.shape[:-1])
        flat = rad.reshape(-1, rad.shape[-1])
        out = np.zeros(flat.shape[0])
        step = 65536  # bounds the (rows, 95) temporaries to ~50 MB
        for lo in range(0, flat.shape[0], step):
            chunk = flat[lo:lo + step]
            p = chunk @ self._check_polynomial.T
            neg = p < 0.0
            rows = np.flatnonzero(neg.any(axis=1))
            if rows.size == 0:
                continue
            p = p[rows]
            gap = chunk[rows] @ self._check_linear.T - p  # l - p > 0 wherever p < 0 (l >= 0)
            with np.errstate(divide="ignore", invalid="ignore"):
                need = np.where(neg[rows], -p / gap, 0.0)
            t0 = need.max(axis=1)
            out[lo + rows] = np.clip(t0 * (1.0 + 2.0 * t0), 0.0, 1.0)
        return out.reshape(rad.shape[:-1])

    def to_xyz(self, radiance: ArrayLike) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2] of radiance (..., n_table) at the table wavelengths."""
        rad = np.asarray(radiance, dtype=float)
        xyz = rad @ self.xyz_polynomial.T
        if self.guarded:
            t = self.linear_weight(rad)
            blend = t > 0.0
            if np.any(blend):
                tb = t[blend][:, None]
                xyz[blend] = (1.0 - tb) * xyz[blend] + tb * (rad[blend] @ self.xyz_linear.T)
        return xyz

    def resample(self, radiance: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Radiance (..., n_table) at the table wavelengths to (..., n) at ``wavelengths`` [nm], never negative."""
        rad = np.asarray(radiance, dtype=float)
        wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
        out = rad @ reconstruction_matrix(self.table_wavelengths, wl, self.atmosphere).T
        if self.guarded:
            t = self.linear_weight(rad)
            blend = t > 0.0
            if np.any(blend):
                linear = _reconstruction(self.table_wavelengths, wl, self.atmosphere, piecewise_linear=True)
                tb = t[blend][:, None]
                out[blend] = (1.0 - tb) * out[blend] + tb * (rad[blend] @ linear.T)
        return np.maximum(out, 0.0)
