"""The sky-model protocol every skyscatter sky answers (see ``docs/conventions.md``).

A sky model maps view directions (unit ENU vectors, shape (..., 3)) to

* ``spectral_radiance(directions, wavelengths)`` [W m^-2 sr^-1 nm^-1], shape (..., n_wavelengths);
* ``xyz(directions)``: CIE 1931 XYZ [cd m^-2], shape (..., 3);
* ``luminance(directions)`` [cd m^-2], shape (...).

Sun-aware models also describe the solar disc separately from the sky: ``sun_direction``,
``sun_solid_angle`` [sr], ``sun_spectral_radiance(wavelengths)`` and ``sun_xyz()``. The sky functions never
include the disc, so integrating a sky over the hemisphere gives diffuse quantities only.

Luminance-only models (CIE, Perez) derive from :class:`LuminanceOnlySky`: their spectra are the luminance
times one fixed relative spectrum (a CIE daylight illuminant at a stated correlated colour temperature).
"""

from __future__ import annotations

import abc
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..conventions import direction_from_angles
from ..errors import InvalidParameterError, SunBelowHorizonError
from ..spectral import (
    HDR_SCALE,
    REFERENCE_WAVELENGTHS,
    as_wavelengths,
    spectrum_to_xyz,
    xyz_to_linear_srgb,
)

__all__ = [
    "LuminanceOnlySky",
    "SkyModel",
    "SUN_ANGULAR_RADIUS",
    "check_sun_angles",
    "solar_disc_solid_angle",
]

#: Mean angular radius of the solar disc seen from the Earth [rad] (Bruneton's 2017 default, 0.2679 deg).
SUN_ANGULAR_RADIUS = 0.004675


def solar_disc_solid_angle(angular_radius: float = SUN_ANGULAR_RADIUS) -> float:
    """Solid angle [sr] of a disc of the given angular radius [rad]: ``2 pi (1 - cos r)`` (6.87e-5 sr for the sun)."""
    return float(2.0 * np.pi * (1.0 - np.cos(angular_radius)))


def check_sun_angles(sun_zenith: float, sun_azimuth: float, *, allow_below_horizon: bool) -> tuple[float, float]:
    """Validate sun angles [rad]; return them as floats (azimuth wrapped into [0, 2 pi)).

    Raises :class:`~skyscatter.errors.SunBelowHorizonError` for a zenith beyond pi/2 when the model cannot
    represent it, and :class:`~skyscatter.errors.InvalidParameterError` for NaN or a zenith outside [0, pi].
    """
    try:
        zen = float(sun_zenith)
        azi = float(sun_azimuth)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError("sun_zenith and sun_azimuth must be scalars in radians") from exc
    if not (np.isfinite(zen) and np.isfinite(azi)):
        raise InvalidParameterError(f"sun angles must be finite radians; got zenith={zen}, azimuth={azi}")
    if not 0.0 <= zen <= np.pi:
        raise InvalidParameterError(f"sun_zenith must be in [0, pi] rad; got {zen:.6g} rad")
    if zen > np.pi / 2 and not allow_below_horizon:
        raise SunBelowHorizonError(
            f"the sun is {np.degrees(zen - np.pi / 2):.3g} deg below the horizon (zenith {np.degrees(zen):.4g} deg);"
            " this model needs a sun zenith angle of at most 90 deg"
        )
    return zen, float(np.mod(azi, 2.0 * np.pi))


class SkyModel(abc.ABC):
    """Abstract sky: radiance as a function of view direction. Subclasses implement ``spectral_radiance``.

    Directions below the horizon (z < 0) return zero unless a model documents otherwise.
    """

    @abc.abstractmethod
    def spectral_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Spectral radiance [W m^-2 sr^-1 nm^-1] of the sky (without the solar disc), shape (..., n_wavelengths).

        Parameters
        ----------
        directions : array_like, shape (..., 3)
            View directions (ENU, pointing from the observer into the sky).
        wavelengths : array_like, optional
            Wavelengths [nm]; default :data:`skyscatter.spectral.DEFAULT_WAVELENGTHS` (380-780 nm, 10 nm).
        """

    def xyz(self, directions: ArrayLike) -> NDArray[np.float64]:
        """CIE 1931 XYZ [cd m^-2] of the sky in ``directions`` (..., 3), integrated over 360-830 nm."""
        return spectrum_to_xyz(self.spectral_radiance(directions, REFERENCE_WAVELENGTHS), REFERENCE_WAVELENGTHS)

    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Luminance [cd m^-2] of the sky in ``directions`` (..., 3)."""
        return self.xyz(directions)[..., 1]

    def rgb(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Linear sRGB in skyscatter's HDR scale (Y = luminance / 683, see ``HDR_SCALE``), shape (..., 3)."""
        return xyz_to_linear_srgb(self.xyz(directions)) * HDR_SCALE

    #: True for models that return radiance for directions that hit the ground (e.g. a precomputed
    #: atmosphere seen from altitude); sky images then do not paint their own ground.
    renders_ground: bool = False
    # Sun-aware models override these.
    has_sun: bool = False

    @property
    def sun_direction(self) -> NDArray[np.float64] | None:
        """Unit ENU vector towards the sun centre, or None for models without a sun."""
        return None


class SunSkyMixin:
    """Helpers for models defined by a sun position (zenith and azimuth in radians)."""

    sun_zenith: float
    sun_azimuth: float
    has_sun = True
    sun_angular_radius: float = SUN_ANGULAR_RADIUS

    @cached_property
    def sun_direction(self) -> NDArray[np.float64]:
        """Unit ENU vector towards the centre of the sun."""
        return direction_from_angles(self.sun_zenith, self.sun_azimuth)

    @property
    def sun_solid_angle(self) -> float:
        """Solid angle of the solar disc [sr]."""
        return solar_disc_solid_angle(self.sun_angular_radius)

    def sun_xyz(self) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2] of the solar disc (its luminance is the Y component).

        Needs the class to define ``sun_spectral_radiance(wavelengths)`` [W m^-2 sr^-1 nm^-1]; luminance-only
        models with a sun override this method instead.
        """
        spectrum = self.sun_spectral_radiance(REFERENCE_WAVELENGTHS)  # type: ignore[attr-defined]
        return spectrum_to_xyz(spectrum, REFERENCE_WAVELENGTHS)

    def _gamma(self, d: NDArray[np.float64]) -> NDArray[np.float64]:
        """Angle [rad] between unit directions ``d`` (..., 3) and the sun, accurate near the sun (atan2 form)."""
        s = self.sun_direction
        cross = np.linalg.norm(np.cross(d, s), axis=-1)
        return np.arctan2(cross, d @ s)

    def _cos_gamma(self, d: NDArray[np.float64]) -> NDArray[np.float64]:
        """Cosine of the angle between unit directions ``d`` (..., 3) and the sun."""
        return np.clip(d @ self.sun_direction, -1.0, 1.0)


class LuminanceOnlySky(SkyModel):
    """A sky defined by luminance alone; spectra are that luminance times a fixed daylight spectrum.

    The relative spectrum is the CIE daylight illuminant at ``cct`` [K] (CIE 15 D-series from the CCT,
    basis from Preetham 1999 A.5); subclasses set ``cct`` (default 6504 K, D65) and implement ``luminance``.
    """

    cct: float = 6504.0

    @abc.abstractmethod
    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Luminance [cd m^-2] of the sky in ``directions`` (..., 3)."""

    @cached_property
    def _relative_spectrum(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        from .. import spectral

        x, y = _daylight_xy(self.cct)
        s = spectral.daylight_spectrum(x, y, REFERENCE_WAVELENGTHS)
        s = s / spectral.spectrum_to_luminance(s, REFERENCE_WAVELENGTHS)  # 1 cd m^-2
        return REFERENCE_WAVELENGTHS, s

    @cached_property
    def _unit_xyz(self) -> NDArray[np.float64]:
        wl, s = self._relative_spectrum
        return spectrum_to_xyz(s, wl)

    def xyz(self, directions: ArrayLike) -> NDArray[np.float64]:
        return self.luminance(directions)[..., None] * self._unit_xyz

    def spectral_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        wl = as_wavelengths(wavelengths)
        ref_wl, s = self._relative_spectrum
        return self.luminance(directions)[..., None] * np.interp(wl, ref_wl, s, left=0.0, right=0.0)


def _daylight_xy(cct: float) -> tuple[float, float]:
    """CIE daylight-locus chromaticity for a correlated colour temperature [K] (CIE 015:2004 Eqs. 3.3-3.4)."""
    from ..spectral import daylight_chromaticity

    x, y = daylight_chromaticity(float(cct))
    return float(x), float(y)
