"""Preetham, Shirley & Smits 1999, "A Practical Analytic Model for Daylight": the skylight model.

Sky luminance Y and chromaticity (x, y) follow the Perez form (Sec. 3.2, Eq. 3-4)::

    F(theta, gamma) = (1 + A exp(B / cos theta)) (1 + C exp(D gamma) + E cos^2 gamma)
    Y = Y_z F(theta, gamma) / F(0, theta_s)       (likewise x and y)

with the distribution coefficients linear in turbidity T and the zenith values Y_z [kcd m^-2], x_z, y_z of
Appendix A.2 (zenith chromaticity matrices with the published 5-digit values, see ``shared/seeds/README.md``).
Spectra are reconstructed from (x, y) with the CIE daylight basis (A.5) and scaled to the model's luminance.
The sun is the A.1 spectral sunlight (:func:`skyscatter.sun.sunlight.sun_spectral_radiance`).

Reference: [Preetham1999].
"""

from __future__ import annotations

import math
import warnings
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..conventions import as_directions
from ..errors import InvalidDirectionError, InvalidParameterError
from ..spectral import (
    LUMINOUS_EFFICACY,
    REFERENCE_WAVELENGTHS,
    as_wavelengths,
    cie_cmfs,
    daylight_basis,
    daylight_coefficients,
    integration_weights,
    xyY_to_xyz,
)
from .base import SkyModel, SunSkyMixin, check_sun_angles
from .perez_family import gradation, indicatrix, perez_f

__all__ = [
    "MAX_TURBIDITY",
    "MIN_TURBIDITY",
    "PreethamSky",
    "perez_f",
    "preetham_coefficients",
    "preetham_zenith_values",
]

#: Smallest turbidity for which the published coefficients keep F(0, theta_s) > 0 for Y: below about 1.64
#: ``1 + A_Y exp(B_Y)`` changes sign and the luminance turns negative (a known limit of the published fit).
MIN_TURBIDITY = 1.65
#: Largest turbidity for which Y_z stays positive with the sun on the horizon: ``-0.2155 T + 2.4192 > 0``
#: needs T < 11.226 (A.2).
MAX_TURBIDITY = 11.0

# A.2: Perez coefficients [A, B, C, D, E] = M @ [T, 1].
_COEFF_Y = np.array(
    [[0.1787, -1.4630], [-0.3554, 0.4275], [-0.0227, 5.3251], [0.1206, -2.5771], [-0.0670, 0.3703]]
)
_COEFF_X = np.array(
    [[-0.0193, -0.2592], [-0.0665, 0.0008], [-0.0004, 0.2125], [-0.0641, -0.8989], [-0.0033, 0.0452]]
)
_COEFF_YCHROMA = np.array(
    [[-0.0167, -0.2608], [-0.0950, 0.0092], [-0.0079, 0.2102], [-0.0441, -1.6537], [-0.0109, 0.0529]]
)
# A.2 zenith chromaticity: x_z = [T^2 T 1] M [theta_s^3 theta_s^2 theta_s 1]^T, theta_s in radians.
_ZENITH_X = np.array(
    [
        [0.00166, -0.00375, 0.00209, 0.0],
        [-0.02903, 0.06377, -0.03202, 0.00394],
        [0.11693, -0.21196, 0.06052, 0.25886],
    ]
)
_ZENITH_Y = np.array(
    [
        [0.00275, -0.00610, 0.00317, 0.0],
        [-0.04214, 0.08970, -0.04153, 0.00516],
        [0.15346, -0.26756, 0.06670, 0.26688],
    ]
)


def preetham_coefficients(turbidity: float) -> dict[str, NDArray[np.float64]]:
    """Perez distribution coefficients (A, B, C, D, E) for Y, x and y (Preetham 1999, Appendix A.2).

    Parameters
    ----------
    turbidity : float
        Atmospheric turbidity T (dimensionless).

    Returns
    -------
    dict
        ``{"Y": array(5), "x": array(5), "y": array(5)}``.
    """
    tv = np.array([turbidity, 1.0])
    return {"Y": _COEFF_Y @ tv, "x": _COEFF_X @ tv, "y": _COEFF_YCHROMA @ tv}


def preetham_zenith_values(turbidity: float, sun_zenith: float) -> tuple[float, float, float]:
    """Zenith luminance Y_z [kcd m^-2] and chromaticity x_z, y_z (Preetham 1999, Appendix A.2).

    ``Y_z = (4.0453 T - 4.9710) tan(chi) - 0.2155 T + 2.4192`` with ``chi = (4/9 - T/120)(pi - 2 theta_s)``;
    x_z, y_z from the 3 x 4 matrices with theta_s in radians.

    Parameters
    ----------
    turbidity : float
        Turbidity T.
    sun_zenith : float
        Sun zenith angle theta_s [rad].
    """
    t = float(turbidity)
    chi = (4.0 / 9.0 - t / 120.0) * (np.pi - 2.0 * sun_zenith)
    y_z = (4.0453 * t - 4.9710) * np.tan(chi) - 0.2155 * t + 2.4192
    tv = np.array([t * t, t, 1.0])
    sv = np.array([sun_zenith**3, sun_zenith**2, sun_zenith, 1.0])
    return float(y_z), float(tv @ _ZENITH_X @ sv), float(tv @ _ZENITH_Y @ sv)


class PreethamSky(SunSkyMixin, SkyModel):
    """The Preetham et al. 1999 analytic clear-sky model (Sec. 3, Appendix A.2 and A.5) with its sun (A.1).

    Parameters
    ----------
    turbidity : float
        Turbidity T (dimensionless, ratio of the optical thickness of haze + molecules to molecules alone).
        The published fit is valid for ``MIN_TURBIDITY <= T <= MAX_TURBIDITY`` (1.65 to 11).
    sun_zenith : float
        Sun zenith angle [rad], 0 to pi/2. The model cannot represent a sun below the horizon
        (:class:`~skyscatter.errors.SunBelowHorizonError`).
    sun_azimuth : float
        Sun azimuth [rad] from north towards east.
    below_horizon : {"zero", "horizon"}
        Radiance for view directions below the horizon: ``"zero"`` (default; the ground is not part of the
        sky) or ``"horizon"`` (the sky value on the horizon at the same azimuth).
    strict : bool
        With True (default) a turbidity outside [1.65, 11] raises
        :class:`~skyscatter.errors.InvalidParameterError`. With False, turbidities in [1, 20] are accepted
        with a :class:`UserWarning`, and any negative luminance the extrapolated fit produces is clipped to 0.
        A turbidity for which the zenith normalisation F(0, theta_s) is not positive always raises.

    Notes
    -----
    Spectra: ``L(lambda) = Y S_D(lambda; x, y) / (683 integral S_D ybar)`` where S_D is the CIE daylight
    spectrum for the chromaticity (Preetham 1999 A.5), normalised on a 5 nm grid over 360-830 nm. Where (x, y)
    lies far from the daylight locus (low sun, near the sun at high turbidity) S_D can dip below zero at
    some wavelengths; those values are clipped to zero.
    """

    model_name = "preetham"

    def __init__(
        self,
        turbidity: float,
        sun_zenith: float,
        sun_azimuth: float,
        *,
        below_horizon: Literal["zero", "horizon"] = "zero",
        strict: bool = True,
    ) -> None:
        t = _check_turbidity(turbidity, strict)
        self.turbidity = t
        self.sun_zenith, self.sun_azimuth = check_sun_angles(sun_zenith, sun_azimuth, allow_below_horizon=False)
        if below_horizon not in ("zero", "horizon"):
            raise InvalidParameterError(f"below_horizon must be 'zero' or 'horizon'; got {below_horizon!r}")
        self.below_horizon = below_horizon
        self.strict = strict
        self._remember(turbidity=t, below_horizon=below_horizon, strict=strict)
        self._coefficients = preetham_coefficients(t)
        y_z, x_z, yc_z = preetham_zenith_values(t, self.sun_zenith)
        self._zenith = {"Y": y_z * 1000.0, "x": x_z, "y": yc_z}
        self._norm = {}
        for key, coeff in self._coefficients.items():
            f0 = float(perez_f(1.0, self.sun_zenith, coeff))
            if not f0 > 0:
                raise InvalidParameterError(
                    f"turbidity {t:g} with sun zenith {np.degrees(self.sun_zenith):.4g} deg gives a non-positive "
                    f"zenith normalisation for {key}; the Preetham fit is valid for T in "
                    f"[{MIN_TURBIDITY}, {MAX_TURBIDITY}]"
                )
            self._norm[key] = f0
        if self._zenith["Y"] <= 0:
            raise InvalidParameterError(
                f"turbidity {t:g} gives a negative zenith luminance at this sun position; "
                f"use T in [{MIN_TURBIDITY}, {MAX_TURBIDITY}]"
            )

    def __repr__(self) -> str:
        return (
            f"PreethamSky(turbidity={self.turbidity:g}, sun_zenith={self.sun_zenith:.6g}, "
            f"sun_azimuth={self.sun_azimuth:.6g})"
        )

    # -- Y, x, y ---------------------------------------------------------------------------------------
    def zenith_luminance(self) -> float:
        """Zenith luminance Y_z [cd m^-2] (A.2; the paper's kcd m^-2 times 1000)."""
        return self._zenith["Y"]

    def _xyY(self, directions: ArrayLike) -> tuple[NDArray, NDArray, NDArray]:  # noqa: N802
        try:
            d = np.asarray(directions)
        except ValueError:  # ragged lists
            d = as_directions(directions)  # raises the standard error
        if d.ndim == 0 or d.shape[-1] != 3 or d.dtype.kind not in "biuf":
            as_directions(d)  # raises the standard shape or type error
        flat = np.asarray(d.reshape(-1, 3), dtype=np.float64)
        coefficients = np.stack([self._coefficients[k] for k in ("x", "y", "Y")])
        scale = np.array([self._zenith[k] / self._norm[k] for k in ("x", "y", "Y")])
        out = np.empty((3, flat.shape[0]))
        n_bad = 0
        sun = np.asarray(self.sun_direction, dtype=np.float64)
        for start in range(0, flat.shape[0], _CHUNK):
            sl = slice(start, start + _CHUNK)
            n_bad += _preetham_xyY(flat[sl], sun, coefficients, scale, self.below_horizon == "horizon",
                                   not self.strict, out[:, sl])
        if n_bad:
            raise InvalidDirectionError(f"directions contain NaN, infinite or zero-length vectors ({n_bad} vectors)")
        x, y, Y = (o.reshape(d.shape[:-1]) for o in out)  # noqa: N806
        return x, y, Y

    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Sky luminance [cd m^-2] for directions (..., 3) (Sec. 3.2: Y = Y_z F(theta, gamma) / F(0, theta_s))."""
        return self._xyY(directions)[2]

    def chromaticity(self, directions: ArrayLike) -> NDArray[np.float64]:
        """CIE 1931 chromaticity (x, y) of the sky, shape (..., 2) (Sec. 3.2 with the A.2 coefficients)."""
        x, y, _ = self._xyY(directions)
        return np.stack([x, y], axis=-1)

    def xyz(self, directions: ArrayLike) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2] of the sky, shape (..., 3), from the model's Y, x, y."""
        x, y, Y = self._xyY(directions)  # noqa: N806
        return xyY_to_xyz(x, y, Y)

    # -- spectra ---------------------------------------------------------------------------------------
    def spectral_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] of the sky, shape (..., n_wavelengths) (A.5).

        Parameters
        ----------
        directions : array_like, shape (..., 3)
            View directions (ENU).
        wavelengths : array_like, optional
            Wavelengths [nm]; default 380-780 nm every 10 nm.
        """
        wl = as_wavelengths(wavelengths)
        x, y, Y = self._xyY(directions)  # noqa: N806
        m1, m2 = daylight_coefficients(x, y)
        # 683 * integral(S_i ybar) on the reference grid, for S0, S1, S2: normalisation is linear in M1, M2.
        ref_y = (cie_cmfs(REFERENCE_WAVELENGTHS)[:, 1] * integration_weights(REFERENCE_WAVELENGTHS)) @ daylight_basis(
            REFERENCE_WAVELENGTHS
        )
        norm = LUMINOUS_EFFICACY * (ref_y[0] + m1 * ref_y[1] + m2 * ref_y[2])
        weights = np.stack([np.ones_like(m1), m1, m2], axis=-1)
        odd = norm <= 0
        if np.any(odd):
            # Far off the daylight locus (only reachable with strict=False) the linear normalisation breaks
            # down; use the luminance of the clipped spectrum itself for those few directions.
            ref_basis = daylight_basis(REFERENCE_WAVELENGTHS)
            ybar = cie_cmfs(REFERENCE_WAVELENGTHS)[:, 1] * integration_weights(REFERENCE_WAVELENGTHS)
            norm = norm.copy()
            norm[odd] = LUMINOUS_EFFICACY * np.maximum(weights[odd] @ ref_basis.T, 0.0) @ ybar
        scale = np.where((Y > 0) & (norm > 0), Y / np.where(norm > 0, norm, 1.0), 0.0)
        basis_t = np.ascontiguousarray(daylight_basis(wl).T)
        # In chunks of directions, written in place: one (N, n_wavelengths) output and cache-sized temporaries
        # (whole-array temporaries made 41 wavelengths at 10^6 directions 7x slower per direction than at 10^5).
        out = np.empty((*scale.shape, wl.size))
        w_flat = weights.reshape(-1, 3)
        s_flat = scale.reshape(-1)
        o_flat = out.reshape(-1, wl.size)
        step = max(1, 65536 // max(wl.size, 1))
        for a in range(0, s_flat.size, step):
            o = o_flat[a:a + step]
            np.matmul(w_flat[a:a + step], basis_t, out=o)
            np.maximum(o, 0.0, out=o)
            o *= s_flat[a:a + step, None]
        return out

    def sun_spectral_radiance(self, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Spectral radiance of the solar disc at the ground [W m^-2 sr^-1 nm^-1] (A.1, Table 2), shape (n,)."""
        from ..sun.sunlight import sun_spectral_radiance

        return sun_spectral_radiance(self.sun_zenith, self.turbidity, as_wavelengths(wavelengths))


#: Directions per vectorised step of :func:`_preetham_xyY` (its temporaries stay in the CPU caches).
_CHUNK = 16384


def _preetham_xyY(d, sun, coefficients, scale, horizon_mode, clip_negative, out) -> int:  # noqa: N802
    """x, y, Y of the Preetham sky into ``out`` (3, n) for the directions ``d`` (n, 3); returns the bad rows.

    Each direction is normalised; NaN, infinite or zero-length vectors are bad (output 0). Below the horizon Y
    is 0 (``horizon_mode``: the direction is moved onto the horizon at its azimuth, at the sun's azimuth if it
    points straight down). Eq. 3 for each channel is the shared Perez-family kernel
    (:mod:`skyscatter.sky.perez_family`) with C = 1 and no Hosek-Wilkie terms.
    """
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        norm = np.sqrt(np.einsum("ij,ij->i", d, d))
        bad = ~((norm > 0.0) & np.isfinite(norm))
        u = d / norm[:, None]
    n_bad = int(np.count_nonzero(bad))
    if n_bad:
        u[bad] = (0.0, 0.0, 1.0)  # any finite direction; its output is zeroed below
    below = u[:, 2] < 0.0
    if horizon_mode and below.any():
        h = np.hypot(u[below, 0], u[below, 1])
        hs = math.hypot(sun[0], sun[1])
        straight_down = (sun[0] / hs, sun[1] / hs) if hs > 0 else (0.0, 1.0)
        flat = np.where((h > 1e-12)[:, None], u[below, :2] / np.where(h > 1e-12, h, 1.0)[:, None],
                        straight_down)
        u[below] = np.column_stack([flat, np.zeros(flat.shape[0])])
        below[:] = False
    dz = u[:, 2]
    cos_gamma = np.clip(u @ sun, -1.0, 1.0)
    gamma = np.arccos(cos_gamma)
    for c in range(3):
        k = coefficients[c]
        f = gradation(dz, k[0], k[1])
        f *= indicatrix(dz, gamma, cos_gamma, 1.0, k[2], k[3], k[4])
        np.multiply(scale[c], f, out=out[c])
    if clip_negative:
        np.maximum(out[2], 0.0, out=out[2])
    out[2, below] = 0.0
    if n_bad:
        out[:, bad] = 0.0
    return n_bad


def _check_turbidity(turbidity: float, strict: bool) -> float:
    try:
        t = float(turbidity)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"turbidity must be a number; got {turbidity!r}") from exc
    if not np.isfinite(t):
        raise InvalidParameterError(f"turbidity must be finite; got {t}")
    if MIN_TURBIDITY <= t <= MAX_TURBIDITY:
        return t
    if strict:
        raise InvalidParameterError(
            f"turbidity {t:g} is outside the Preetham model's valid range [{MIN_TURBIDITY}, {MAX_TURBIDITY}]"
            " (below 1.64 the fitted luminance turns negative, above 11.2 the zenith luminance does);"
            " pass strict=False to extrapolate within [1, 20] with a warning"
        )
    if not 1.0 <= t <= 20.0:
        raise InvalidParameterError(f"turbidity must be within [1, 20] even with strict=False; got {t:g}")
    warnings.warn(
        f"turbidity {t:g} is outside the Preetham fit's range [{MIN_TURBIDITY}, {MAX_TURBIDITY}]; "
        "negative luminances are clipped to zero",
        UserWarning,
        stacklevel=3,
    )
    return t
