"""The sky-model protocol every skyscatter sky answers (see ``docs/conventions.md`` and ``docs/architecture.md``).

A sky model maps view directions (unit ENU vectors, shape (..., 3)) to

* ``spectral_radiance(directions, wavelengths)`` [W m^-2 sr^-1 nm^-1], shape (..., n_wavelengths);
* ``xyz(directions)``: CIE 1931 XYZ [cd m^-2], shape (..., 3);
* ``luminance(directions)`` [cd m^-2], shape (...);
* ``rgb(directions)``: linear sRGB in the HDR scale (Y = luminance / 683).

and declares, so that callers never probe it with ``hasattr``:

* ``sun``: the solar disc as a :class:`SolarDisc` (direction, angular radius, spectral radiance, XYZ, limb
  darkening where the model has it), or None for models without a sun. The sky functions never include the
  disc, so integrating a sky over the hemisphere gives diffuse quantities only.
* ``renders_ground``: True when the model returns radiance for directions that hit the ground.
* ``turbidity``: the Linke-style turbidity the analytic aerial perspective (Preetham 1999, Sec. 4) needs, or None.
* ``model_name``, ``model_parameters()``, ``to_dict()``: the model's registry entry and its parameters, so that
  :func:`skyscatter.sky.registry.from_dict` rebuilds it (pickling goes the same way).

Luminance-only models (CIE, Perez) derive from :class:`LuminanceOnlySky`: their spectra are the luminance
times one fixed relative spectrum (a CIE daylight illuminant at a stated correlated colour temperature).
"""

from __future__ import annotations

import abc
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any, ClassVar

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

# Re-exported: the solar disc's size is defined in the sun layer (skyscatter.sun.disc).
from ..sun.disc import SUN_ANGULAR_RADIUS, solar_disc_solid_angle

__all__ = [
    "LuminanceOnlySky",
    "SkyModel",
    "SolarDisc",
    "SUN_ANGULAR_RADIUS",
    "check_sun_angles",
    "solar_disc_solid_angle",
]

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


@dataclass(frozen=True, eq=False)
class SolarDisc:
    """The solar disc of a sky model, reported separately from the sky (the protocol's ``sky.sun``).

    Attributes
    ----------
    direction : ndarray, shape (3,)
        Unit ENU vector towards the centre of the disc.
    angular_radius : float
        Angular radius of the disc [rad].
    spectral_radiance : callable
        ``spectral_radiance(wavelengths [nm]) -> (n,)``: radiance averaged over the disc [W m^-2 sr^-1 nm^-1].
    xyz : callable
        ``xyz() -> (3,)``: CIE 1931 XYZ of the disc-averaged radiance [cd m^-2].
    limb_darkening : callable or None
        ``limb_darkening(r, wavelengths [nm]) -> (..., n)``: radiance at relative radius ``r`` in [0, 1] of the
        disc divided by the disc average (so its area-weighted mean is 1); None for a uniform disc.
    normal_illuminance : float or None
        The illuminance [lx] on a plane facing the sun where the model defines the disc by it (the CIE and Perez
        skies); None: disc-averaged luminance times solid angle.
    """

    direction: NDArray[np.float64]
    angular_radius: float
    spectral_radiance: Callable[[ArrayLike], NDArray[np.float64]]
    xyz: Callable[[], NDArray[np.float64]]
    limb_darkening: Callable[[ArrayLike, ArrayLike], NDArray[np.float64]] | None = None
    normal_illuminance: float | None = None

    @property
    def solid_angle(self) -> float:
        """Solid angle of the disc [sr]: ``2 pi (1 - cos r)``."""
        return solar_disc_solid_angle(self.angular_radius)

    def luminance(self) -> float:
        """Disc-averaged luminance [cd m^-2]."""
        return float(np.asarray(self.xyz(), dtype=float)[1])

    def illuminance_normal(self) -> float:
        """Illuminance [lx] on a plane facing the sun: disc-averaged luminance times solid angle."""
        if self.normal_illuminance is not None:
            return self.normal_illuminance
        return self.luminance() * self.solid_angle

    def spectral_irradiance_normal(self, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Spectral irradiance [W m^-2 nm^-1] on a plane facing the sun."""
        return np.asarray(self.spectral_radiance(as_wavelengths(wavelengths)), dtype=float) * self.solid_angle

    @property
    def above_horizon(self) -> bool:
        """True while any part of the disc is above the horizon."""
        return bool(self.direction[2] > -np.sin(self.angular_radius))


class SkyModel(abc.ABC):
    """Abstract sky: radiance as a function of view direction. Subclasses implement ``spectral_radiance``.

    Directions below the horizon (z < 0) return zero unless a model documents otherwise (``renders_ground``).
    """

    #: Registry name of the model (:mod:`skyscatter.sky.registry`); None for unregistered helper skies.
    model_name: ClassVar[str | None] = None
    #: True for models that return radiance for directions that hit the ground (e.g. a precomputed
    #: atmosphere seen from altitude); sky images then do not paint their own ground.
    renders_ground: ClassVar[bool] = False
    #: Linke-style turbidity for the analytic aerial perspective (Preetham 1999 Sec. 4); None if the model has none.
    turbidity: float | None = None

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

    # -- the sun -------------------------------------------------------------------------------------------
    @property
    def sun(self) -> SolarDisc | None:
        """The solar disc (reported separately from the sky), or None for models without a sun."""
        return None

    @property
    def has_sun(self) -> bool:
        """True when the model has a solar disc (``sun`` is not None)."""
        return self.sun is not None

    @property
    def sun_direction(self) -> NDArray[np.float64] | None:
        """Unit ENU vector towards the sun centre, or None for models without a sun."""
        return None

    def sun_shadow(self, points: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64] | None:
        """The factor by which the sunlight reaching ``points`` (n, 3) [m] (x east, y north, z above the ground at
        the observer's foot) differs from the solar disc :attr:`sun` seen by the observer, at ``wavelengths`` [nm],
        (n, n_wl): for a sky with a 3D cloud field, the field's transmittance to the sun from each point over that
        from the eye. None for skies whose sunlight does not vary between points (every sky without a 3D field).
        Renderers multiply the sunlight on their surfaces by it (cloud shadows on terrain)."""
        return None

    # -- registry and serialisation ------------------------------------------------------------------------
    def model_parameters(self) -> dict[str, Any]:
        """The keyword arguments that rebuild this sky with the registry (sun angles excluded)."""
        return dict(getattr(self, "_model_parameters", {}))

    def _remember(self, **parameters: Any) -> None:
        """Record the constructor's parameters for :meth:`model_parameters` (called by subclasses' ``__init__``)."""
        self._model_parameters = parameters

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-able description: model name, sun angles [rad] and parameters (see ``registry.from_dict``)."""
        from .registry import to_dict

        return to_dict(self)

    def __reduce_ex__(self, protocol: Any) -> Any:
        # Registered skies pickle as their description and are rebuilt on unpickling, so that Dask workers get
        # the same sky without shipping caches or compiled kernels (a precomputed atmosphere is re-read from
        # the table cache). Unregistered helper skies pickle as ordinary objects.
        if self.model_name is not None:
            from .registry import from_dict

            return (from_dict, (self.to_dict(),))
        return super().__reduce_ex__(protocol)


class SunSkyMixin:
    """Helpers for models defined by a sun position (zenith and azimuth in radians)."""

    sun_zenith: float
    sun_azimuth: float
    sun_angular_radius: float = SUN_ANGULAR_RADIUS

    @property
    def sun(self) -> SolarDisc:
        """The solar disc: the model's ``sun_spectral_radiance`` and ``sun_xyz`` at ``sun_direction``."""
        return SolarDisc(
            direction=self.sun_direction,
            angular_radius=self.sun_angular_radius,
            spectral_radiance=self.sun_spectral_radiance,  # type: ignore[attr-defined]
            xyz=self.sun_xyz,
            limb_darkening=self.sun_limb_darkening,
        )

    #: Relative radiance across the disc (see :class:`SolarDisc`); None: a uniform disc.
    sun_limb_darkening: Callable[[ArrayLike, ArrayLike], NDArray[np.float64]] | None = None

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
