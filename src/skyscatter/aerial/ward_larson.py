"""Ward-Larson's ambient aerial perspective, as Preetham, Shirley & Smits (1999) reconstruct it for Figure 8.

Sec. 5: "Our implementation of Ward-Larson's model uses the correct luminance but the relative spectral curve
of the zenith. It correctly sets the attenuation at one kilometer and uses an exponential interpolant
elsewhere. For in-scattering it uses the product of the zenith spectral radiance and the complement of the
attenuation factor." So, with tau_1 the extinction of a 1 km horizontal path at the observer's height
(Eq. 7):

    tau(s) = tau_1 ** (s / 1 km),      L_in(s) = L_zenith (1 - tau(s)),

the same in every direction (the "ambient" in-scattering of the Radiance system). :class:`ConstantColourSky`
gives the matching sky: a luminance distribution (e.g. the CIE clear sky) with one relative spectrum (e.g. the
zenith's) everywhere.

Reference: [Preetham1999].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere import mie_total_scattering, rayleigh_total_scattering
from ..errors import InvalidParameterError
from ..sky.base import SkyModel, SolarDisc
from ..spectral import REFERENCE_WAVELENGTHS, as_wavelengths, spectrum_to_luminance, spectrum_to_xyz
from .base import AerialPerspective, check_path, check_rays
from .integrals import ALPHA_HAZE, ALPHA_MOLECULES
from .preetham import resolve_turbidity

__all__ = ["ConstantColourSky", "WardLarsonAerialPerspective"]

_ZENITH = np.array([0.0, 0.0, 1.0])


class WardLarsonAerialPerspective(AerialPerspective):
    """Direction-independent ("ambient") aerial perspective of Preetham et al. 1999, Sec. 5 / Figure 8.

    Parameters
    ----------
    sky : SkyModel
        Sky whose zenith spectral radiance is the in-scattered colour.
    turbidity : float, optional
        Haze turbidity [-] of the 1 km extinction; default ``sky.turbidity``.
    reference_distance : float
        The distance [m] at which the extinction is exact (1 km in the paper).
    """

    def __init__(self, sky: SkyModel, *, turbidity: float | None = None, reference_distance: float = 1000.0) -> None:
        if not (np.isfinite(reference_distance) and reference_distance > 0):
            raise InvalidParameterError(f"reference_distance must be a positive length [m]; got {reference_distance!r}")
        self.sky = sky
        self.turbidity = resolve_turbidity(sky, turbidity)
        self.reference_distance = float(reference_distance)

    def __repr__(self) -> str:
        return f"WardLarsonAerialPerspective({self.sky!r}, turbidity={self.turbidity:g})"

    def _tau(self, s: NDArray, h: NDArray, wl: NDArray) -> NDArray:
        # Eq. 7 for a horizontal path of reference_distance at the observer's height, raised to s / reference.
        depth = (mie_total_scattering(wl, self.turbidity) * np.exp(-ALPHA_HAZE * h)[..., None]
                 + rayleigh_total_scattering(wl) * np.exp(-ALPHA_MOLECULES * h)[..., None]) * self.reference_distance
        return np.exp(-depth * (s / self.reference_distance)[..., None])

    def transmittance(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """``tau_1km ** (s / 1 km)``, shape (..., n_wavelengths); arguments as in the protocol."""
        _, s, h, wl = check_path(directions, distances, observer_height, wavelengths)
        return self._tau(s, h, wl)

    def evaluate_rays(self, origins: ArrayLike, directions: ArrayLike, distances: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(tau, ``L_zenith (1 - tau)`` [W m^-2 sr^-1 nm^-1]) of paths from ``origins`` (ENU [m]; only their
        height ``z`` matters), each (..., n_wavelengths)."""
        o, _, s, wl = check_rays(origins, directions, distances, wavelengths)
        h = o[..., 2]
        tau = self._tau(s, h, wl)
        zenith = np.asarray(self.sky.spectral_radiance(_ZENITH, wl), dtype=float)
        return tau, zenith * (1.0 - tau)


class ConstantColourSky(SkyModel):
    """A sky with the luminance of another model and one fixed relative spectrum everywhere.

    Parameters
    ----------
    luminance_sky : SkyModel
        Gives the luminance distribution [cd m^-2] (its ``luminance``) and, if it has one, the sun's
        position and illuminance.
    spectrum : array_like
        Relative spectral shape (any positive scale) sampled at ``spectrum_wavelengths``.
    spectrum_wavelengths : array_like
        Wavelengths [nm] of ``spectrum``.

    The solar disc (if ``luminance_sky`` has one) keeps its own luminance and gets the same relative
    spectrum. Used for Figure 8's CIE clear sky (the zenith spectrum of the Preetham sky).
    """

    def __init__(self, luminance_sky: SkyModel, spectrum: ArrayLike, spectrum_wavelengths: ArrayLike) -> None:
        wl = as_wavelengths(spectrum_wavelengths)
        sp = np.asarray(spectrum, dtype=float)
        if sp.shape != wl.shape or not np.all(np.isfinite(sp)) or np.any(sp < 0) or not np.any(sp > 0):
            raise InvalidParameterError("spectrum must be finite, >= 0, not all zero, one value per wavelength")
        self.luminance_sky = luminance_sky
        self._wl = wl
        unit = np.interp(REFERENCE_WAVELENGTHS, wl, sp, left=0.0, right=0.0)
        self._scale = 1.0 / float(spectrum_to_luminance(unit, REFERENCE_WAVELENGTHS))
        self._spectrum = sp * self._scale  # 1 cd m^-2
        self.turbidity = luminance_sky.turbidity

    def __repr__(self) -> str:
        return f"ConstantColourSky({self.luminance_sky!r})"

    def _relative(self, wavelengths: ArrayLike | None) -> NDArray[np.float64]:
        wl = as_wavelengths(wavelengths)
        return np.interp(wl, self._wl, self._spectrum, left=0.0, right=0.0)

    @property
    def sun(self) -> SolarDisc | None:
        """The luminance sky's solar disc (direction, size) with this sky's spectrum; None without a sun."""
        disc = self.luminance_sky.sun
        if disc is None:
            return None
        return SolarDisc(direction=disc.direction, angular_radius=disc.angular_radius,
                         spectral_radiance=self.sun_spectral_radiance, xyz=self.sun_xyz)

    @property
    def sun_direction(self) -> NDArray[np.float64] | None:
        return self.luminance_sky.sun_direction

    @property
    def sun_solid_angle(self) -> float:
        """Solid angle [sr] of the solar disc (0 without a sun)."""
        disc = self.luminance_sky.sun
        return 0.0 if disc is None else disc.solid_angle

    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        return np.asarray(self.luminance_sky.luminance(directions), dtype=float)

    def spectral_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        return self.luminance(directions)[..., None] * self._relative(wavelengths)

    def sun_spectral_radiance(self, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Solar disc radiance [W m^-2 sr^-1 nm^-1]: the luminance sky's disc luminance times the spectrum."""
        disc = self.luminance_sky.sun
        if disc is None:
            return np.zeros_like(as_wavelengths(wavelengths))
        lum = spectrum_to_luminance(disc.spectral_radiance(REFERENCE_WAVELENGTHS), REFERENCE_WAVELENGTHS)
        return float(lum) * self._relative(wavelengths)

    def sun_xyz(self) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2] of the solar disc (zeros without a sun)."""
        return spectrum_to_xyz(self.sun_spectral_radiance(REFERENCE_WAVELENGTHS), REFERENCE_WAVELENGTHS)
