"""CIE sky luminance distributions: overcast (Moon & Spencer), clear (Kittler, CIE 1973), standard general sky.

* CIE overcast sky (Moon & Spencer 1942, adopted by the CIE in 1955), Preetham et al. 1999 Eq. 2:
  ``L = L_z (1 + 2 cos theta) / 3``.
* CIE 1973 clear sky (Kittler), Preetham et al. 1999 Eq. 1::

      L / L_z = (0.91 + 10 exp(-3 gamma) + 0.45 cos^2 gamma) (1 - exp(-0.32 / cos theta))
                / ((0.91 + 10 exp(-3 Z_s) + 0.45 cos^2 Z_s) (1 - exp(-0.32)))

* CIE S 011/E:2003 = ISO 15469:2004 standard general sky, 15 types: relative luminance
  ``L / L_z = f(chi) phi(Z) / (f(Z_s) phi(0))`` with the gradation ``phi(Z) = 1 + a exp(b / cos Z)``
  (``phi(pi/2) = 1``) and the scattering indicatrix ``f(chi) = 1 + c [exp(d chi) - exp(d pi/2)] + e cos^2 chi``,
  parameters a-e from the standard's Table 1 (``skyscatter/data/cie2003_sky_types.csv``); Z is the zenith
  angle of the sky element, chi its angular distance from the sun, Z_s the sun's zenith angle (lecture
  ``004``, Eqs. 2-3, gives the same form).

The standards define relative distributions. The absolute scale comes from the zenith luminance L_z
[cd m^-2] or from the horizontal diffuse illuminance D_v [lx] (``L_z = D_v / integral (L/L_z) cos theta
dOmega``, integrated with :func:`skyscatter.photometry.plane_integral`). Given neither, the sky is scaled to
``D_v = DEFAULT_DIFFUSE_ILLUMINANCE`` = 10 000 lx, a typical overcast daylight level.

Spectra: these are luminance-only models; their spectrum is the CIE daylight illuminant at ``cct`` (default
6504 K, D65) scaled to the luminance. The distributions describe the sky without the sun: the solar disc has
the illuminance ``sun_illuminance_normal`` [lx] (default 0; set it to add a sun to images and to
``horizontal_illuminance(..., include_sun=True)``). Directions below the horizon have zero luminance.

References: [CIE2003]; [Kittler1967] as [CIE1973]; [MoonSpencer1942].
"""

from __future__ import annotations

import abc
import dataclasses
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere.tables import load_table
from ..conventions import as_directions
from ..errors import InvalidParameterError
from ..quadrature import plane_integral
from ..spectral import as_wavelengths
from . import registry
from .base import LuminanceOnlySky, SolarDisc, SunSkyMixin, check_sun_angles
from .perez_family import cie_parameters, extended_perez, kittler_parameters

__all__ = [
    "DEFAULT_DIFFUSE_ILLUMINANCE",
    "SKY_TYPE_DESCRIPTIONS",
    "CIEClearSky",
    "CIEOvercastSky",
    "CIEStandardSky",
    "LuminanceSunMixin",
    "cie_gradation",
    "cie_indicatrix",
    "cie_sky_parameters",
    "cie_standard_relative_luminance",
    "kittler_clear_relative_luminance",
    "overcast_relative_luminance",
]

#: Horizontal diffuse illuminance [lx] a CIE sky is scaled to when neither scale is given.
DEFAULT_DIFFUSE_ILLUMINANCE = 10_000.0

#: Short descriptions of the 15 CIE 2003 sky types (abridged from ISO 15469 Table 1).
SKY_TYPE_DESCRIPTIONS = {
    1: "CIE standard overcast sky: steep gradation towards zenith, azimuthal uniformity",
    2: "overcast: steep gradation and slight brightening towards the sun",
    3: "overcast: moderately graded with azimuthal uniformity",
    4: "overcast: moderately graded and slight brightening towards the sun",
    5: "sky of uniform luminance",
    6: "partly cloudy: no gradation towards zenith, slight brightening towards the sun",
    7: "partly cloudy: no gradation towards zenith, brighter circumsolar region",
    8: "partly cloudy: no gradation towards zenith, distinct solar corona",
    9: "partly cloudy, with the obscured sun",
    10: "partly cloudy, with brighter circumsolar region",
    11: "white-blue sky with distinct solar corona",
    12: "CIE standard clear sky, low luminance turbidity",
    13: "CIE standard clear sky, polluted atmosphere",
    14: "cloudless turbid sky with broad solar corona",
    15: "white-blue turbid sky with broad solar corona",
}



def cie_sky_parameters(sky_type: int) -> tuple[float, float, float, float, float]:
    """Gradation (a, b) and indicatrix (c, d, e) parameters of CIE 2003 sky type 1-15 (ISO 15469, Table 1)."""
    t = _check("cie", "sky_type", sky_type)
    table = load_table("cie2003_sky_types")
    i = int(np.flatnonzero(table["type"] == t)[0])
    return tuple(float(table[k][i]) for k in "abcde")  # type: ignore[return-value]


def _check(model: str, name: str, value):
    """``value`` checked against the registry's range of ``name`` (the rule stated once, with its reason)."""
    spec = registry.get(model)
    return spec.parameter(name).check(value, spec.name)


def cie_gradation(cos_zenith: ArrayLike, a: float, b: float) -> NDArray[np.float64]:
    """Gradation function ``phi(Z) = 1 + a exp(b / cos Z)`` (CIE S 011/E:2003), with ``phi(pi/2) = 1``.

    Parameters
    ----------
    cos_zenith : array_like
        Cosine of the sky element's zenith angle, in [0, 1].
    a, b : float
        Gradation parameters (b < 0 for all 15 standard types).
    """
    return extended_perez(np.clip(np.asarray(cos_zenith, dtype=float), 0.0, 1.0), 0.0,
                          np.array([a, b, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]))


def cie_indicatrix(chi: ArrayLike, c: float, d: float, e: float) -> NDArray[np.float64]:
    """Scattering indicatrix ``f(chi) = 1 + c [exp(d chi) - exp(d pi/2)] + e cos^2 chi`` (CIE S 011/E:2003).

    Parameters
    ----------
    chi : array_like
        Angular distance between the sky element and the sun [rad].
    """
    return extended_perez(1.0, chi, cie_parameters(0.0, 0.0, c, d, e))


def cie_standard_relative_luminance(
    sky_type: int, cos_zenith: ArrayLike, chi: ArrayLike, sun_zenith: float
) -> NDArray[np.float64]:
    """``L / L_z = f(chi) phi(Z) / (f(Z_s) phi(0))`` for CIE 2003 sky type 1-15 (ISO 15469).

    Parameters
    ----------
    sky_type : int
        1-15.
    cos_zenith : array_like
        Cosine of the element's zenith angle Z (>= 0).
    chi : array_like
        Angular distance of the element from the sun [rad].
    sun_zenith : float
        Solar zenith angle Z_s [rad] (the zenith's distance from the sun).
    """
    k = cie_parameters(*cie_sky_parameters(sky_type))
    return extended_perez(np.clip(np.asarray(cos_zenith, dtype=float), 0.0, 1.0), chi, k) / extended_perez(
        1.0, sun_zenith, k)


def overcast_relative_luminance(cos_zenith: ArrayLike) -> NDArray[np.float64]:
    """Moon & Spencer / CIE overcast sky ``L / L_z = (1 + 2 cos theta) / 3`` (Preetham et al. 1999, Eq. 2)."""
    return (1.0 + 2.0 * np.asarray(cos_zenith, dtype=float)) / 3.0


def kittler_clear_relative_luminance(
    cos_zenith: ArrayLike, gamma: ArrayLike, sun_zenith: float
) -> NDArray[np.float64]:
    """CIE 1973 clear sky (Kittler) ``L / L_z`` (Preetham et al. 1999, Eq. 1).

    ``(0.91 + 10 exp(-3 gamma) + 0.45 cos^2 gamma)(1 - exp(-0.32 / cos theta))`` divided by the same at the
    zenith (gamma = Z_s, theta = 0); ``1 - exp(-0.32 / cos theta)`` tends to 1 at the horizon.
    """
    k = kittler_parameters()
    return extended_perez(np.clip(np.asarray(cos_zenith, dtype=float), 0.0, 1.0), gamma, k) / extended_perez(
        1.0, sun_zenith, k)


class LuminanceSunMixin:
    """Solar disc of a luminance-only sky from its normal illuminance ``sun_illuminance_normal`` [lx].

    The disc is uniform, of luminance ``E_n / sun_solid_angle`` [cd m^-2], with the sky's relative spectrum
    (the CIE daylight illuminant at ``cct``).
    """

    sun_illuminance_normal: float | None = 0.0

    @property
    def sun(self) -> SolarDisc:
        """The uniform solar disc that carries ``sun_illuminance_normal`` [lx] (0 once the sun has set)."""
        disc = SunSkyMixin.sun.fget(self)  # type: ignore[attr-defined]
        given = float(self.sun_illuminance_normal or 0.0) if self.sun_luminance() > 0 else 0.0
        return dataclasses.replace(disc, normal_illuminance=given)

    def sun_luminance(self) -> float:
        """Luminance of the solar disc [cd m^-2] (0 when the sun's illuminance is unknown or the sun is set)."""
        e = self.sun_illuminance_normal
        if not e or self.sun_direction[2] < -np.sin(self.sun_angular_radius):  # type: ignore[attr-defined]
            return 0.0
        return float(e) / self.sun_solid_angle  # type: ignore[attr-defined]

    def sun_xyz(self) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2] of the solar disc."""
        return self.sun_luminance() * self._unit_xyz  # type: ignore[attr-defined]

    def sun_spectral_radiance(self, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Spectral radiance of the solar disc [W m^-2 sr^-1 nm^-1], shape (n_wavelengths,)."""
        wl = as_wavelengths(wavelengths)
        ref_wl, s = self._relative_spectrum  # type: ignore[attr-defined]
        return self.sun_luminance() * np.interp(wl, ref_wl, s, left=0.0, right=0.0)


class _ScaledCIESky(LuminanceOnlySky):
    """Shared absolute scaling: relative luminance times L_z, L_z from either scale or the default."""

    zenith_luminance: float

    def relative_luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """``L / L_z`` for view directions (..., 3); 0 below the horizon."""
        d = as_directions(directions)
        cos_z = d[..., 2]
        rel = self._relative(d)
        return np.where(cos_z >= 0.0, rel, 0.0)

    @abc.abstractmethod
    def _relative(self, d: NDArray[np.float64]) -> NDArray[np.float64]:
        """``L / L_z`` for unit directions (..., 3) in the upper hemisphere."""

    def relative_diffuse_illuminance(self) -> float:
        """``integral (L / L_z) cos theta dOmega`` over the sky [sr]; D_v = L_z times this."""
        return plane_integral(self.relative_luminance)

    def _set_scale(self, zenith_luminance, diffuse_illuminance, **parameters) -> None:
        """Set L_z from the given scale and record the model's parameters (``parameters``: the others)."""
        if zenith_luminance is not None and diffuse_illuminance is not None:
            raise InvalidParameterError(
                "give either zenith_luminance [cd m^-2] or diffuse_illuminance [lx] to scale the sky, not both")
        lz = _check(self.model_name, "zenith_luminance", zenith_luminance)
        dv = _check(self.model_name, "diffuse_illuminance", diffuse_illuminance)
        self._remember(**parameters, zenith_luminance=lz, diffuse_illuminance=None if lz is not None else dv)
        if lz is None:
            dv = DEFAULT_DIFFUSE_ILLUMINANCE if dv is None else dv
            lz = dv / self.relative_diffuse_illuminance()
        self.zenith_luminance = float(lz)

    @cached_property
    def diffuse_illuminance(self) -> float:
        """Horizontal diffuse illuminance of the sky [lx]."""
        return self.zenith_luminance * self.relative_diffuse_illuminance()

    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Sky luminance [cd m^-2] for view directions (..., 3); 0 below the horizon."""
        return self.zenith_luminance * self.relative_luminance(directions)


class CIEOvercastSky(_ScaledCIESky):
    """CIE overcast sky (Moon & Spencer 1942): ``L = L_z (1 + 2 cos theta) / 3`` (Preetham et al. 1999, Eq. 2).

    Parameters
    ----------
    zenith_luminance : float, optional
        Zenith luminance L_z [cd m^-2].
    diffuse_illuminance : float, optional
        Horizontal diffuse illuminance D_v [lx]; ``L_z = 9 D_v / (7 pi)``. Give at most one of the two; with
        neither, D_v = 10 000 lx (``DEFAULT_DIFFUSE_ILLUMINANCE``, L_z = 4092.6 cd m^-2).

    The sky has no sun (``has_sun`` is False). Spectra: CIE D65 scaled to the luminance.
    """

    model_name = "cie-overcast"

    def __init__(self, *, zenith_luminance: float | None = None, diffuse_illuminance: float | None = None) -> None:
        self._set_scale(zenith_luminance, diffuse_illuminance)

    def __repr__(self) -> str:
        return f"CIEOvercastSky(zenith_luminance={self.zenith_luminance:.6g})"

    def relative_diffuse_illuminance(self) -> float:
        """``integral (1 + 2 cos theta)/3 cos theta dOmega = 7 pi / 9`` [sr] (closed form)."""
        return 7.0 * np.pi / 9.0

    def _relative(self, d: NDArray[np.float64]) -> NDArray[np.float64]:
        return overcast_relative_luminance(np.clip(d[..., 2], 0.0, 1.0))


class CIEClearSky(LuminanceSunMixin, SunSkyMixin, _ScaledCIESky):
    """CIE 1973 clear sky (Kittler; Preetham et al. 1999, Eq. 1) for a sun at (sun_zenith, sun_azimuth).

    Parameters
    ----------
    sun_zenith : float
        Solar zenith angle [rad], at most pi/2.
    sun_azimuth : float
        Solar azimuth [rad, from north towards east].
    zenith_luminance : float, optional
        Zenith luminance L_z [cd m^-2].
    diffuse_illuminance : float, optional
        Horizontal diffuse illuminance D_v [lx]. Give at most one; with neither, D_v = 10 000 lx.
    sun_illuminance_normal : float
        Direct normal illuminance of the sun [lx] for the solar disc (default 0: the formula is the sky only).
    """

    model_name = "cie-clear"

    def __init__(
        self,
        sun_zenith: float,
        sun_azimuth: float,
        *,
        zenith_luminance: float | None = None,
        diffuse_illuminance: float | None = None,
        sun_illuminance_normal: float = 0.0,
    ) -> None:
        self.sun_zenith, self.sun_azimuth = check_sun_angles(sun_zenith, sun_azimuth, allow_below_horizon=False)
        self.sun_illuminance_normal = _check(self.model_name, "sun_illuminance_normal", sun_illuminance_normal)
        self._set_scale(zenith_luminance, diffuse_illuminance, sun_illuminance_normal=self.sun_illuminance_normal)

    def __repr__(self) -> str:
        return (
            f"CIEClearSky(sun_zenith={self.sun_zenith:.6g}, sun_azimuth={self.sun_azimuth:.6g}, "
            f"zenith_luminance={self.zenith_luminance:.6g})"
        )

    def _relative(self, d: NDArray[np.float64]) -> NDArray[np.float64]:
        gamma = self._gamma(d)
        return kittler_clear_relative_luminance(np.clip(d[..., 2], 0.0, 1.0), gamma, self.sun_zenith)


class CIEStandardSky(LuminanceSunMixin, SunSkyMixin, _ScaledCIESky):
    """CIE S 011/E:2003 (ISO 15469:2004) standard general sky of type 1-15.

    ``L = L_z f(chi) phi(Z) / (f(Z_s) phi(0))`` with the standard's gradation and indicatrix functions and
    Table 1 parameters (:func:`cie_sky_parameters`; :data:`SKY_TYPE_DESCRIPTIONS`).

    Parameters
    ----------
    sky_type : int
        1 (overcast, steep gradation) to 15 (white-blue turbid sky with broad solar corona); 12 is the CIE
        standard clear sky.
    sun_zenith : float
        Solar zenith angle [rad], at most pi/2.
    sun_azimuth : float
        Solar azimuth [rad, from north towards east].
    zenith_luminance : float, optional
        Zenith luminance L_z [cd m^-2].
    diffuse_illuminance : float, optional
        Horizontal diffuse illuminance D_v [lx], integrated numerically. Give at most one; with neither,
        D_v = 10 000 lx (``DEFAULT_DIFFUSE_ILLUMINANCE``).
    sun_illuminance_normal : float
        Direct normal illuminance of the sun [lx] for the solar disc (default 0: the standard is the sky only).
    """

    model_name = "cie"

    def __init__(
        self,
        sky_type: int,
        sun_zenith: float,
        sun_azimuth: float,
        *,
        zenith_luminance: float | None = None,
        diffuse_illuminance: float | None = None,
        sun_illuminance_normal: float = 0.0,
    ) -> None:
        self.sky_type = _check(self.model_name, "sky_type", sky_type)
        self.parameters = cie_sky_parameters(self.sky_type)
        self.sun_zenith, self.sun_azimuth = check_sun_angles(sun_zenith, sun_azimuth, allow_below_horizon=False)
        self.sun_illuminance_normal = _check(self.model_name, "sun_illuminance_normal", sun_illuminance_normal)
        self._extended = cie_parameters(*self.parameters)
        self._norm = float(extended_perez(1.0, self.sun_zenith, self._extended))
        self._set_scale(zenith_luminance, diffuse_illuminance, sky_type=self.sky_type,
                        sun_illuminance_normal=self.sun_illuminance_normal)

    def __repr__(self) -> str:
        return (
            f"CIEStandardSky(sky_type={self.sky_type}, sun_zenith={self.sun_zenith:.6g}, "
            f"sun_azimuth={self.sun_azimuth:.6g}, zenith_luminance={self.zenith_luminance:.6g})"
        )

    @property
    def description(self) -> str:
        """The standard's description of this sky type."""
        return SKY_TYPE_DESCRIPTIONS[self.sky_type]

    def _relative(self, d: NDArray[np.float64]) -> NDArray[np.float64]:
        return extended_perez(np.clip(d[..., 2], 0.0, 1.0), self._gamma(d), self._extended) / self._norm

