"""The ASRC-CIE sky: four CIE-type luminance distributions weighted by Perez's sky clearness and brightness.

Seed ``002`` (Preetham's course notes, "ASRC-CIE model luminance model", citing Littlefair 1994) describes the
model as "a linear combination of four luminance models - the standard CIE cloudless sky, a high turbidity
formulation of the latter, a realistic formulation for intermediate skies proposed by Nakamura and the standard
CIE overcast sky", weighted by "the sky clearness and sky brightness factors" (Perez et al. 1990). The seed gives
neither the weights nor the two new components. Both are restated, with the same four skies, in the daylighting
model of DOE-2.1E as EnergyPlus carries it; that public restatement is what this module implements:

* EnergyPlus Engineering Reference, "Time-Step Daylighting Calculation", section "Time-Step Sky Luminance"
  (``doc/engineering-reference/src/daylighting-and-window-calculations/time-step-daylighting-calculation.tex``,
  its third to eighth equations; "the interpolation factors are a function of sky clearness and sky brightness
  (Perez et al., 1990)"), and the same rule in ``DayltgInteriorIllum`` of ``src/EnergyPlus/DaylightingManager.cc``
  ("Based on DOE-2.1E subroutine DINTIL");
* the component skies: the same reference, "Daylight Factor Calculation", section "Sky Luminance
  Distributions", and LBNL's DElight (``dskylu``, sky types 0-3), the C version of the DOE-2 daylighting code.

The primary papers ([Perez1992]; [Littlefair1994]) were not available; the identification rests on the
same four components and the same two indices (docs/standard_skies.md lists what each source gives).

**Weights.** With epsilon the sky clearness and delta the sky brightness (Perez et al. 1990, Eqs. 1-2), the sky
is a linear interpolation between two neighbouring skies of the sequence overcast - intermediate - turbid -
clear, each normalised to its zenith luminance (psi = L / L_z)::

    epsilon <= 1.2:        psi = s psi_intermediate + (1 - s) psi_overcast,
                           s = min{1, max[0, (epsilon - 1) / 0.2, (delta - 0.05) / 0.4]}
    1.2 < epsilon <= 3:    psi = s psi_turbid + (1 - s) psi_intermediate,        s = (epsilon - 1.2) / 1.8
    epsilon > 3:           psi = s psi_clear + (1 - s) psi_turbid,               s = min[1, (epsilon - 3) / 3]

The weights are continuous in epsilon and delta; epsilon >= 6 gives the pure CIE clear sky, epsilon = 1 with
delta <= 0.05 the pure CIE overcast sky. Since every component has psi = 1 at the zenith, so has the blend; the
absolute sky is ``L = D_v psi / integral(psi cos theta dOmega)`` (the diffuse illuminance D_v reproduced by
construction, as the Perez and CIE skies do; EnergyPlus's ``HorIllSkyFac`` is the same scaling).

**Components** (theta, Z: zenith angles of the sky element and of the sun; gamma: their angular distance):

* clear: CIE 1973 (Kittler), ``(0.91 + 10 e^(-3 gamma) + 0.45 cos^2 gamma)(1 - e^(-0.32 / cos theta))`` over its
  zenith value (:func:`skyscatter.sky.cie.kittler_clear_relative_luminance`);
* turbid: CIE 1973 for a polluted atmosphere (Kittler), ``(0.856 + 16 e^(-3 gamma) + 0.3 cos^2 gamma)
  (1 - e^(-0.32 / cos theta))`` over its zenith value (:func:`kittler_turbid_relative_luminance`; CIE
  S 011/E:2003 type 13 to rounding). The engineering reference prints 10 for 16 in this sky's denominator; the
  denominator is the numerator at the zenith (as in DElight's ``dskylu``), so 16;
* intermediate (Nakamura et al. 1985; CIE 110-1994), as Radiance's ``skybright.cal`` (``intersky``) writes it::

      [(1.35 sin(5.631 - 3.59 theta) + 3.12) sin(4.396 - 2.6 Z) + 6.37 - theta] / 2.326
          * exp(-0.563 gamma ((2.629 - theta)(1.562 - Z) + 0.812))

  over its zenith value (:func:`intermediate_relative_luminance`). EnergyPlus writes the same formula in
  altitudes with constants rounded differently (e.g. ``sin(3.59 phi - 0.009)`` for ``sin(5.631 - 3.59 theta)``);
  the two agree within 0.7 % relative to the zenith (tests);
* overcast: CIE (Moon & Spencer 1942), ``(1 + 2 cos theta) / 3``.

The components are positive on the whole upper hemisphere for every sun (the intermediate sky's smallest value
relative to its zenith is 0.029, with the sun at the zenith), so the blend needs no clamping.

**Sky condition, limits and errors.** The inputs, their checks, the guards on epsilon and delta and the
luminous efficacies are those of the Perez sky (:func:`skyscatter.sky.perez.perez_sky_condition`): the same hour
gives both skies the same epsilon, delta, diffuse illuminance and sun. The guards change no weight (the weights
saturate below delta = 0.05, above delta = 0.45 and above epsilon = 6, inside the clamps [0.01, 0.6] and
epsilon <= 11.9); they act on the efficacies only. The sun for the distribution is the true one (the CIE forms
need no altitude clamp).

**Sun.** A separate uniform disc carrying the Perez 1990 direct normal illuminance ``sun_illuminance_normal``
[lx]. Spectra: CIE D65 scaled to the luminance. Directions below the horizon: 0.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..conventions import as_directions
from ..quadrature import plane_integral
from .base import LuminanceOnlySky, SunSkyMixin
from .cie import LuminanceSunMixin, overcast_relative_luminance
from .perez import DEFAULT_DEW_POINT, perez_sky_condition
from .perez_family import extended_perez, gradation, indicatrix, kittler_parameters, kittler_turbid_parameters

__all__ = [
    "COMPONENTS",
    "ASRCCIESky",
    "asrc_cie_relative_luminance",
    "asrc_cie_weights",
    "intermediate_relative_luminance",
    "kittler_turbid_relative_luminance",
]

#: The four component skies, in the order of :func:`asrc_cie_weights`' last axis.
COMPONENTS = ("clear", "turbid", "intermediate", "overcast")


def asrc_cie_weights(epsilon: ArrayLike, delta: ArrayLike) -> NDArray[np.float64]:
    """Weights of the clear, turbid, intermediate and overcast skies, shape (..., 4); they sum to 1.

    The interpolation of the EnergyPlus Engineering Reference, "Time-Step Sky Luminance" (module docstring):
    ``s_is,os = min{1, max[0, (epsilon - 1)/0.2, (delta - 0.05)/0.4]}`` for epsilon <= 1.2,
    ``s_ts,is = (epsilon - 1.2)/1.8`` for 1.2 < epsilon <= 3, ``s_cs,ts = min[1, (epsilon - 3)/3]`` above.

    Parameters
    ----------
    epsilon : array_like
        Sky clearness (Perez et al. 1990, Eq. 1), >= 1.
    delta : array_like
        Sky brightness (Perez et al. 1990, Eq. 2), >= 0; it matters only for epsilon <= 1.2.
    """
    eps, dl = np.broadcast_arrays(np.asarray(epsilon, dtype=float), np.asarray(delta, dtype=float))
    low = eps <= 1.2
    high = eps > 3.0
    mid = ~low & ~high
    s_io = np.clip(np.maximum((eps - 1.0) / 0.2, (dl - 0.05) / 0.4), 0.0, 1.0)
    s_ti = np.clip((eps - 1.2) / 1.8, 0.0, 1.0)
    s_ct = np.clip((eps - 3.0) / 3.0, 0.0, 1.0)
    out = np.zeros(eps.shape + (4,))
    out[..., 0] = np.where(high, s_ct, 0.0)
    out[..., 1] = np.where(high, 1.0 - s_ct, np.where(mid, s_ti, 0.0))
    out[..., 2] = np.where(mid, 1.0 - s_ti, np.where(low, s_io, 0.0))
    out[..., 3] = np.where(low, 1.0 - s_io, 0.0)
    return out


def kittler_turbid_relative_luminance(cos_zenith: ArrayLike, gamma: ArrayLike, sun_zenith: ArrayLike
                                      ) -> NDArray[np.float64]:
    """CIE 1973 clear sky for a turbid atmosphere (Kittler) ``L / L_z`` (module docstring, "turbid").

    Parameters
    ----------
    cos_zenith : array_like
        Cosine of the sky element's zenith angle (clipped to [0, 1]).
    gamma : array_like
        Angular distance of the element from the sun [rad].
    sun_zenith : array_like
        Solar zenith angle [rad]; broadcasts against the angles (one per hour in a sky matrix).
    """
    k = kittler_turbid_parameters()
    return extended_perez(np.clip(np.asarray(cos_zenith, dtype=float), 0.0, 1.0), gamma, k) / extended_perez(
        1.0, sun_zenith, k)


def _intermediate(theta: ArrayLike, gamma: ArrayLike, sun_zenith: ArrayLike) -> NDArray[np.float64]:
    """The unnormalised intermediate sky of Radiance's skybright.cal (``intersky`` without ``A2 / A4``)."""
    t = np.asarray(theta, dtype=float)
    z = np.asarray(sun_zenith, dtype=float)
    # the factors of theta alone and of Z alone first (directions x hours in a sky matrix: one product each)
    grad = (1.35 * np.sin(5.631 - 3.59 * t) + 3.12) * (np.sin(4.396 - 2.6 * z) / 2.326) + (6.37 - t) / 2.326
    expo = np.asarray(((2.629 - t) * (1.562 - z) + 0.812) * np.asarray(gamma, dtype=float), dtype=float)
    expo *= -0.563
    np.exp(expo, out=expo)
    expo *= grad
    return expo


def intermediate_relative_luminance(cos_zenith: ArrayLike, gamma: ArrayLike, sun_zenith: ArrayLike
                                    ) -> NDArray[np.float64]:
    """Intermediate sky (Nakamura et al. 1985; CIE 110-1994) ``L / L_z``, as Radiance's ``skybright.cal``.

    Arguments as :func:`kittler_turbid_relative_luminance`; the formula is in the module docstring.
    """
    theta = np.arccos(np.clip(np.asarray(cos_zenith, dtype=float), 0.0, 1.0))
    z = np.asarray(sun_zenith, dtype=float)
    return _intermediate(theta, gamma, z) / _intermediate(0.0, z, z)


def asrc_cie_relative_luminance(cos_zenith: ArrayLike, gamma: ArrayLike, sun_zenith: ArrayLike,
                                weights: ArrayLike, cos_gamma: ArrayLike | None = None) -> NDArray[np.float64]:
    """The blend ``psi = sum_k w_k psi_k`` (relative to the zenith) for directions in the upper hemisphere.

    The clear and turbid skies share their gradation ``1 - exp(-0.32 / cos theta)`` and the exponent of
    ``exp(-3 gamma)``, so their weighted sum is one Perez-family form with per-sky coefficients
    ``C = sum w_k C_k / N_k``, ``D = sum w_k D_k / N_k``, ``F = sum w_k F_k / N_k`` (N_k: each sky's zenith
    value) evaluated by :func:`skyscatter.sky.perez_family.gradation` and ``indicatrix`` (exact; one
    exponential per direction instead of two). A component whose weight is 0 everywhere is not evaluated.

    Parameters
    ----------
    cos_zenith, gamma, sun_zenith : array_like
        As :func:`kittler_turbid_relative_luminance`; all broadcast together (e.g. (n,) directions against
        (hours, 1) suns).
    weights : array_like, shape (..., 4)
        :func:`asrc_cie_weights`; ``weights[..., k]`` broadcasts against the angles.
    cos_gamma : array_like, optional
        ``cos(gamma)`` when the caller has it (saves a cosine per direction).
    """
    w = np.asarray(weights, dtype=float)
    ct = np.clip(np.asarray(cos_zenith, dtype=float), 0.0, 1.0)
    gam = np.asarray(gamma, dtype=float)
    z = np.asarray(sun_zenith, dtype=float)
    out = np.zeros(np.broadcast_shapes(ct.shape, gam.shape, z.shape, w.shape[:-1]))
    w_clear, w_turbid, w_inter, w_over = (w[..., k] for k in range(4))
    if np.any(w_clear != 0.0) or np.any(w_turbid != 0.0):
        kc, kt = kittler_parameters(), kittler_turbid_parameters()
        a = w_clear / extended_perez(1.0, z, kc)  # weight over the zenith value N_k
        b = w_turbid / extended_perez(1.0, z, kt)
        cg = np.cos(gam) if cos_gamma is None else np.asarray(cos_gamma, dtype=float)
        ind = indicatrix(ct, gam, cg, a * kc[2] + b * kt[2], a * kc[3] + b * kt[3], kc[4], a * kc[5] + b * kt[5])
        out += gradation(ct, kc[0], kc[1]) * ind
    if np.any(w_inter != 0.0):
        out += w_inter * intermediate_relative_luminance(ct, gam, z)
    if np.any(w_over != 0.0):
        out += w_over * overcast_relative_luminance(ct)
    return out


class ASRCCIESky(LuminanceSunMixin, SunSkyMixin, LuminanceOnlySky):
    """ASRC-CIE sky: the CIE clear, turbid, intermediate and overcast skies weighted by epsilon and delta.

    Parameters are those of :class:`~skyscatter.sky.perez.PerezSky` (same units, ranges, defaults and errors):

    Parameters
    ----------
    sun_zenith : float
        Solar zenith angle [rad], at most pi/2.
    sun_azimuth : float
        Solar azimuth [rad, from north towards east].
    epsilon, delta : float, optional
        Sky clearness (>= 1) and brightness (>= 0), given together. With neither these nor the irradiances:
        epsilon 6.5, delta 0.15 (the pure CIE clear sky).
    diffuse_illuminance : float, optional
        Horizontal diffuse illuminance D_v [lx]; default: from the irradiance (or from delta) with the Perez
        1990 diffuse luminous efficacy.
    direct_normal_irradiance, diffuse_horizontal_irradiance : float, optional
        I_n >= 0 and D_h > 0 [W m^-2]; give both instead of epsilon and delta.
    day_of_year : int, optional
        1-366, for the Sun-Earth distance in delta; default: the mean distance.
    dew_point : float
        Surface dew point [deg C] for the luminous efficacies; default 11.
    guards : bool
        The Perez sky's guards on epsilon, delta and the sun altitude for the efficacies (default True).

    Attributes
    ----------
    epsilon, delta : float
        The sky condition used (after the guards).
    weights : dict
        Weight of each of :data:`COMPONENTS`.
    zenith_luminance : float
        L_z [cd m^-2].
    diffuse_illuminance : float
        D_v [lx]; the sky integrates to it.
    sun_illuminance_normal : float
        Direct normal illuminance [lx] of the solar disc (Perez 1990 direct efficacy).
    guards_applied : list of str
        Which guards changed the sky condition.
    """

    model_name = "asrc-cie"

    def __init__(
        self,
        sun_zenith: float,
        sun_azimuth: float,
        *,
        epsilon: float | None = None,
        delta: float | None = None,
        diffuse_illuminance: float | None = None,
        direct_normal_irradiance: float | None = None,
        diffuse_horizontal_irradiance: float | None = None,
        day_of_year: int | None = None,
        dew_point: float = DEFAULT_DEW_POINT,
        guards: bool = True,
    ) -> None:
        c = perez_sky_condition(
            sun_zenith, sun_azimuth, epsilon=epsilon, delta=delta, diffuse_illuminance=diffuse_illuminance,
            direct_normal_irradiance=direct_normal_irradiance,
            diffuse_horizontal_irradiance=diffuse_horizontal_irradiance, day_of_year=day_of_year,
            dew_point=dew_point, guards=guards,
        )
        self._remember(**c.model_parameters)
        p = c.parameters
        self.sun_zenith, self.sun_azimuth = c.sun_zenith, c.sun_azimuth
        self.day_of_year, self.dew_point, self.guards = c.day_of_year, c.dew_point, c.guards
        self.guards_applied = list(c.notes)
        self.epsilon = float(p.epsilon)
        self.delta = float(p.delta)
        self.diffuse_illuminance = float(p.diffuse_illuminance)
        self.sun_illuminance_normal = float(p.sun_illuminance_normal)
        self.diffuse_horizontal_irradiance = float(p.diffuse_horizontal_irradiance)
        self.direct_normal_irradiance = float(p.direct_normal_irradiance)
        self.precipitable_water = float(p.water)
        self._weights = asrc_cie_weights(self.epsilon, self.delta)
        self.weights = {k: float(v) for k, v in zip(COMPONENTS, self._weights, strict=True)}
        self.zenith_luminance = self.diffuse_illuminance / plane_integral(self.relative_luminance)

    def __repr__(self) -> str:
        w = ", ".join(f"{k}={v:.3g}" for k, v in self.weights.items() if v > 0)
        return (
            f"ASRCCIESky(sun_zenith={self.sun_zenith:.6g}, sun_azimuth={self.sun_azimuth:.6g}, "
            f"epsilon={self.epsilon:.4g}, delta={self.delta:.4g}, weights: {w})"
        )

    def relative_luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """``L / L_z`` for view directions (..., 3); 0 below the horizon."""
        d = as_directions(directions)
        rel = asrc_cie_relative_luminance(d[..., 2], self._gamma(d), self.sun_zenith, self._weights)
        return np.where(d[..., 2] >= 0.0, rel, 0.0)

    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Sky luminance [cd m^-2] for view directions (..., 3); 0 below the horizon."""
        return self.zenith_luminance * self.relative_luminance(directions)
