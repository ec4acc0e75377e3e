"""Fit the Hosek-Wilkie sky form to any sky model: the analytic form for any atmosphere skyscatter can compute.

The form is that of Hosek & Wilkie 2012 ([HosekWilkie2012] Eqs. 9-12): per wavelength,
``L = F(theta, gamma; A..I) * L_M`` with the nine parameters and L_M quintic Bezier curves of
``t = (eta / (pi/2))^(1/3)`` (eta the solar elevation), six control points each. The authors fitted each
elevation first and the curves afterwards (Sec. 5); here the 6 x 10 control values per wavelength are fitted
jointly to all sampled elevations at once by nonlinear least squares (``scipy.optimize.least_squares``,
trust-region reflective) on the relative error ``L_fit / L_source - 1``, starting from the published
coefficients (turbidity ``initial_turbidity``, albedo ``initial_albedo``, linear between bands). The overall
scale shared by L_M and the linear parameters C, D, F, G, I is left free (the solver's damping keeps it where it
starts).

The source is any callable ``make_sky(sun_zenith, sun_azimuth)`` returning a sky model (the precomputed
atmosphere for some :class:`~skyscatter.atmosphere.AtmosphereParameters`, a Monte Carlo sky, a measured-data
interpolant, or the published model itself); only its ``spectral_radiance`` is used.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from ..conventions import direction_from_angles
from ..errors import InvalidParameterError
from ..sky.base import SkyModel
from ..sky.hosek_wilkie import HosekWilkieDataset, bezier_weights, published_dataset
from ..sky.perez_family import hosek_wilkie_f, hosek_wilkie_f_jacobian

__all__ = ["default_sample_directions", "fit_hosek_wilkie", "fit_sun_elevations", "sky_fit_error"]


def fit_sun_elevations(n: int = 16) -> NDArray[np.float64]:
    """Sun elevations [rad] evenly spaced in the Bezier parameter t = (eta / (pi/2))^(1/3), horizon to zenith."""
    t = np.linspace(0.0, 1.0, n)
    return t**3 * (np.pi / 2.0)


def default_sample_directions(min_elevation_deg: float = 1.0) -> NDArray[np.float64]:
    """Fit directions (n, 3) relative to a sun at azimuth 0: elevations dense near the horizon, azimuth 0-180 deg.

    Only half the sky is sampled: the form and clear-sky models are symmetric about the sun's vertical plane.
    """
    elev = np.radians([min_elevation_deg, 2.0, 3.5, 5.0, 7.5, 10, 13, 17, 22, 28, 35, 43, 52, 62, 73, 84, 90])
    elev = elev[elev >= np.radians(min_elevation_deg)]
    azi = np.radians(np.concatenate([[0.0, 2.0, 5.0], np.arange(10.0, 181.0, 10.0)]))
    ee, aa = np.meshgrid(elev, azi, indexing="ij")
    d = direction_from_angles(np.pi / 2 - ee.ravel(), aa.ravel())
    keep = np.ones(d.shape[0], bool)
    keep[(ee.ravel() == np.pi / 2) & (aa.ravel() > 0)] = False  # one zenith sample
    return d[keep]


def _initial_guess(wavelength: float, turbidity: float, albedo: float) -> tuple[NDArray, NDArray]:
    """Published control points (6, 9) and L_M (6,) at a turbidity/albedo, linear between bands (clamped)."""
    ds = published_dataset()
    wl = float(np.clip(wavelength, ds.wavelengths[0], ds.wavelengths[-1]))
    params = np.zeros((6, 9))
    rad = np.zeros(6)
    j = min(int(np.searchsorted(ds.wavelengths, wl, side="right")) - 1, ds.wavelengths.size - 2)
    f = (wl - ds.wavelengths[j]) / (ds.wavelengths[j + 1] - ds.wavelengths[j])
    it = int(np.clip(round(turbidity), 1, 10)) - 1
    for band, wb in ((j, 1 - f), (j + 1, f)):
        for ia, wa in ((0, 1 - albedo), (1, albedo)):
            params += wb * wa * ds.params[band, ia, it]
            rad += wb * wa * ds.radiance[band, ia, it]
    return params, rad


def _geometry(directions: NDArray[np.float64], elevations: NDArray[np.float64]) -> tuple[NDArray, NDArray]:
    """cos theta (n_d,) and gamma (n_e, n_d) for suns at azimuth 0 and the given elevations."""
    sun = direction_from_angles(np.pi / 2 - elevations, 0.0)  # (n_e, 3)
    cross = np.linalg.norm(np.cross(directions[None, :, :], sun[:, None, :]), axis=-1)
    gamma = np.arctan2(cross, sun @ directions.T)
    return directions[:, 2], gamma


def _model(x: NDArray[np.float64], bern: NDArray, cos_t: NDArray, gamma: NDArray) -> NDArray[np.float64]:
    """Radiance (n_e, n_d) of the form with control values x = [6 x 9 params, 6 L_M] at the sampled elevations."""
    ctrl = x[:54].reshape(6, 9)
    params = bern @ ctrl  # (n_e, 9)
    lm = bern @ x[54:]  # (n_e,)
    return hosek_wilkie_f(cos_t[None, :], gamma, params[:, None, :]) * lm[:, None]


def _model_jacobian(x: NDArray[np.float64], bern: NDArray, cos_t: NDArray, gamma: NDArray
                    ) -> NDArray[np.float64]:
    """d(model)/dx, shape (n_e, n_d, 60): the chain rule through the Bezier weights (params = bern @ ctrl)."""
    ctrl = x[:54].reshape(6, 9)
    params = bern @ ctrl
    lm = bern @ x[54:]
    df = hosek_wilkie_f_jacobian(cos_t[None, :], gamma, params[:, None, :])  # (n_e, n_d, 9)
    f = hosek_wilkie_f(cos_t[None, :], gamma, params[:, None, :])  # (n_e, n_d)
    jac_ctrl = (df * lm[:, None, None])[:, :, None, :] * bern[:, None, :, None]  # (n_e, n_d, 6, 9)
    jac_lm = f[:, :, None] * bern[:, None, :]  # (n_e, n_d, 6)
    n_e, n_d = f.shape
    return np.concatenate([jac_ctrl.reshape(n_e, n_d, 54), jac_lm], axis=-1)


def fit_hosek_wilkie(
    make_sky: Callable[[float, float], SkyModel],
    wavelengths: ArrayLike,
    *,
    sun_elevations: ArrayLike | None = None,
    directions: ArrayLike | None = None,
    sun_exclusion_deg: float = 1.0,
    initial_turbidity: float = 3.0,
    initial_albedo: float = 0.1,
    max_evaluations: int = 500,
    provenance: dict[str, Any] | None = None,
) -> HosekWilkieDataset:
    """Fit the Hosek-Wilkie form to the sky models ``make_sky(sun_zenith, 0)`` at several sun elevations.

    Parameters
    ----------
    make_sky : callable
        ``make_sky(sun_zenith [rad], sun_azimuth [rad]) -> SkyModel`` for one atmosphere.
    wavelengths : array_like
        Wavelengths [nm] to fit (each independently), increasing.
    sun_elevations : array_like, optional
        Sun elevations [rad] to sample, in [0, pi/2]; default :func:`fit_sun_elevations` (16, even in t).
        At least 6 (one per control point).
    directions : array_like, shape (n, 3), optional
        Sample directions for a sun at azimuth 0 (default :func:`default_sample_directions`).
    sun_exclusion_deg : float
        Samples closer than this to the sun [deg] are left out (the disc and its immediate aureole).
    initial_turbidity, initial_albedo : float
        Published coefficients to start from (turbidity 1-10, albedo 0-1).
    max_evaluations : int
        Cap on residual evaluations per wavelength.
    provenance : dict, optional
        JSON-able description of the source (e.g. ``AtmosphereParameters.to_dict()``), stored in the dataset.

    Returns
    -------
    HosekWilkieDataset
        One atmosphere (albedo and turbidity axes of length 1); ``provenance`` holds the caller's description,
        the fit settings, ``repr`` of a source sky and the RMS relative error per wavelength and elevation.
    """
    wl = np.atleast_1d(np.asarray(wavelengths, dtype=np.float64))
    if wl.ndim != 1 or wl.size == 0 or not np.all(np.isfinite(wl)) or np.any(np.diff(wl) <= 0):
        raise InvalidParameterError(f"wavelengths must be a non-empty increasing 1-D array [nm]; got {wl}")
    elev = fit_sun_elevations() if sun_elevations is None else np.asarray(sun_elevations, dtype=np.float64)
    if elev.ndim != 1 or elev.size < 6 or np.any(~np.isfinite(elev)) or np.any((elev < 0) | (elev > np.pi / 2)):
        raise InvalidParameterError("sun_elevations must be at least 6 values in [0, pi/2] rad")
    if not (1.0 <= initial_turbidity <= 10.0 and 0.0 <= initial_albedo <= 1.0):
        raise InvalidParameterError("initial_turbidity must be in [1, 10] and initial_albedo in [0, 1]")
    d = default_sample_directions() if directions is None else np.asarray(directions, dtype=np.float64)
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    cos_t, gamma = _geometry(d, elev)
    use = gamma > np.radians(sun_exclusion_deg)
    t = np.power(elev / (np.pi / 2), 1.0 / 3.0)
    bern = np.stack([bezier_weights(v) for v in t])  # (n_e, 6)

    started = time.perf_counter()
    source = np.stack([make_sky(np.pi / 2 - e, 0.0).spectral_radiance(d, wl) for e in elev])  # (n_e, n_d, n_wl)
    if not np.all(np.isfinite(source)):
        raise InvalidParameterError("the source sky returned non-finite radiance at the fit samples")
    sample_seconds = time.perf_counter() - started
    params = np.zeros((wl.size, 1, 1, 6, 9))
    rad = np.zeros((wl.size, 1, 1, 6))
    rms = np.zeros((wl.size, elev.size))
    for k, w in enumerate(wl):
        src = source[..., k]
        ok = use & (src > 0)
        if np.count_nonzero(ok) < 60:
            raise InvalidParameterError(f"too few positive source samples at {w:g} nm to fit the form")
        x0p, x0r = _initial_guess(w, initial_turbidity, initial_albedo)
        # Start L_M from the source's zenith radiance over the initial F at the zenith (least squares in t).
        zen = np.argmax(d[:, 2])
        f_zen = np.array([hosek_wilkie_f(1.0, gamma[j, zen], bern[j] @ x0p) for j in range(elev.size)])
        lm_target = src[:, zen] / np.where(np.abs(f_zen) > 1e-9, f_zen, 1.0)
        x0r = np.linalg.lstsq(bern, lm_target, rcond=None)[0]
        x0 = np.concatenate([x0p.ravel(), x0r])
        target = src[ok]

        def residuals(x: NDArray[np.float64], target=target, ok=ok) -> NDArray[np.float64]:
            r = _model(x, bern, cos_t, gamma)[ok] / target - 1.0
            return np.where(np.isfinite(r), r, 1e3)

        def jacobian(x: NDArray[np.float64], target=target, ok=ok) -> NDArray[np.float64]:
            jac = _model_jacobian(x, bern, cos_t, gamma)[ok] / target[:, None]
            return np.where(np.isfinite(jac), jac, 0.0)

        sol = least_squares(residuals, x0, jac=jacobian, method="lm", x_scale="jac", max_nfev=max_evaluations)
        params[k, 0, 0] = sol.x[:54].reshape(6, 9)
        rad[k, 0, 0] = sol.x[54:]
        rel = np.where(ok, _model(sol.x, bern, cos_t, gamma) / np.where(ok, src, 1.0) - 1.0, np.nan)
        rms[k] = np.sqrt(np.nanmean(rel**2, axis=1))

    example = make_sky(np.pi / 4, 0.0)
    prov = {
        "source": provenance or {},
        "source_repr": repr(example),
        "fit": {
            "method": "scipy.optimize.least_squares trf, relative residuals, control points of all elevations jointly",
            "sun_elevations_deg": np.degrees(elev).round(6).tolist(),
            "n_directions": int(d.shape[0]),
            "sun_exclusion_deg": float(sun_exclusion_deg),
            "initial_turbidity": float(initial_turbidity),
            "initial_albedo": float(initial_albedo),
            "rms_relative_error_at_samples": rms.round(6).tolist(),
            "sampling_seconds": round(sample_seconds, 3),
            "total_seconds": round(time.perf_counter() - started, 3),
        },
    }
    return HosekWilkieDataset(wl, params, rad, albedos=[0.0], turbidities=[1.0], provenance=prov)


def sky_fit_error(
    fitted: SkyModel,
    source: SkyModel,
    wavelengths: ArrayLike,
    *,
    min_elevation_deg: float = 5.0,
    sun_exclusion_deg: float = 5.0,
    n: int = 4000,
    seed: int = 0,
) -> NDArray[np.float64]:
    """RMS relative error ``fitted / source - 1`` per wavelength over random sky directions.

    The region is the one the fit's accuracy target is stated on (docs/hosek_wilkie.md): at least
    ``min_elevation_deg`` above the horizon and ``sun_exclusion_deg`` from the sun; ``n`` directions uniform in solid
    angle there.
    """
    rng = np.random.default_rng(seed)
    lo = np.sin(np.radians(min_elevation_deg))
    d = direction_from_angles(np.arccos(rng.uniform(lo, 1.0, 4 * n)), rng.uniform(0, 2 * np.pi, 4 * n))
    sun = np.asarray(source.sun_direction)
    d = d[d @ sun < np.cos(np.radians(sun_exclusion_deg))][:n]
    wl = np.atleast_1d(np.asarray(wavelengths, dtype=float))
    a = fitted.spectral_radiance(d, wl)
    b = source.spectral_radiance(d, wl)
    return np.sqrt(np.mean((a / b - 1.0) ** 2, axis=0))

