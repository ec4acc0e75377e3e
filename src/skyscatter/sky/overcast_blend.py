"""Preetham's clear sky blended towards the CIE overcast sky at high turbidity (Preetham et al. 1999, Sec. 5).

Preetham et al. render their high-turbidity example (T = 10, Fig. 7 bottom) with "the CIE overcast sky
luminance and a flat spectral curve" and note that "for intermediate turbidities our model and the overcast
model should be interpolated between as recommended for the CIE luminance models". The paper gives no weights;
this module uses a linear blend in turbidity, a documented choice:

    w(T) = clip((T - T_start) / (T_end - T_start), 0, 1)        (defaults T_start = 6, T_end = 10)
    L(d) = (1 - w) L_Preetham(d) + w L_z (1 + 2 cos theta) / 3

T_start = 6 is the largest turbidity in Preetham's simulations (2-6), T_end = 10 the paper's overcast example.
The overcast part takes the Preetham zenith luminance L_z = Y_z(T, theta_s) (A.2), so the zenith luminance does
not change with w. Its spectrum is flat (equal energy per nm, CIE illuminant E) scaled to its luminance; the sky's
spectrum and XYZ are the same blend of the two parts. The solar disc is Preetham's sunlight times (1 - w): the
sun fades behind the overcast. Valid turbidities are those of :class:`~skyscatter.PreethamSky` (1.65 to 11).

Reference: [Preetham1999].
"""

from __future__ import annotations

from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..conventions import as_directions
from ..errors import InvalidParameterError
from ..spectral import REFERENCE_WAVELENGTHS, as_wavelengths, spectrum_to_luminance, spectrum_to_xyz
from .base import SkyModel, SunSkyMixin
from .cie import overcast_relative_luminance
from .preetham import PreethamSky

__all__ = ["PreethamOvercastBlendSky", "overcast_weight"]


def overcast_weight(turbidity: float, start: float = 6.0, end: float = 10.0) -> float:
    """Weight w in [0, 1] of the overcast sky at turbidity T: ``clip((T - start) / (end - start), 0, 1)``."""
    if not (np.isfinite(start) and np.isfinite(end) and end > start):
        raise InvalidParameterError(f"blend needs finite start < end; got start={start!r}, end={end!r}")
    return float(np.clip((float(turbidity) - start) / (end - start), 0.0, 1.0))


class PreethamOvercastBlendSky(SunSkyMixin, SkyModel):
    """Preetham sky blended linearly in turbidity towards a flat-spectrum CIE overcast sky (see module notes).

    Parameters
    ----------
    turbidity : float
        Atmospheric turbidity T, 1.65 to 11.
    sun_zenith, sun_azimuth : float
        Sun position [rad]; azimuth from north towards east; zenith at most pi/2.
    blend_start, blend_end : float
        Turbidities where the overcast weight starts rising from 0 and reaches 1 (default 6 and 10).
    """

    model_name = "preetham-overcast"

    def __init__(
        self,
        turbidity: float,
        sun_zenith: float,
        sun_azimuth: float,
        *,
        blend_start: float = 6.0,
        blend_end: float = 10.0,
    ) -> None:
        self.clear = PreethamSky(turbidity, sun_zenith, sun_azimuth)
        self._remember(turbidity=self.clear.turbidity, blend_start=float(blend_start), blend_end=float(blend_end))
        self.turbidity = self.clear.turbidity
        self.sun_zenith, self.sun_azimuth = self.clear.sun_zenith, self.clear.sun_azimuth
        self.weight = overcast_weight(self.turbidity, float(blend_start), float(blend_end))
        self.zenith_luminance = self.clear.zenith_luminance()

    def __repr__(self) -> str:
        return (
            f"PreethamOvercastBlendSky(turbidity={self.turbidity:g}, sun_zenith={self.sun_zenith:.6g}, "
            f"sun_azimuth={self.sun_azimuth:.6g}, overcast_weight={self.weight:.3g})"
        )

    @cached_property
    def _flat_unit(self) -> float:
        """Equal-energy spectral radiance [W m^-2 sr^-1 nm^-1] with a luminance of 1 cd m^-2."""
        return 1.0 / float(spectrum_to_luminance(np.ones_like(REFERENCE_WAVELENGTHS), REFERENCE_WAVELENGTHS))

    def overcast_luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Luminance [cd m^-2] of the overcast part, ``L_z (1 + 2 cos theta) / 3``, 0 below the horizon."""
        d = as_directions(directions)
        z = d[..., 2]
        return np.where(z >= 0.0, self.zenith_luminance * overcast_relative_luminance(np.clip(z, 0.0, 1.0)), 0.0)

    def luminance(self, directions: ArrayLike) -> NDArray[np.float64]:
        """Blended luminance [cd m^-2]."""
        w = self.weight
        out = w * self.overcast_luminance(directions)
        if w < 1.0:
            out = out + (1.0 - w) * self.clear.luminance(directions)
        return out

    def xyz(self, directions: ArrayLike) -> NDArray[np.float64]:
        """CIE XYZ [cd m^-2]: the blend of Preetham's XYZ and the flat-spectrum overcast sky."""
        w = self.weight
        unit = spectrum_to_xyz(np.full_like(REFERENCE_WAVELENGTHS, self._flat_unit), REFERENCE_WAVELENGTHS)
        out = w * self.overcast_luminance(directions)[..., None] * unit
        if w < 1.0:
            out = out + (1.0 - w) * self.clear.xyz(directions)
        return out

    def spectral_radiance(self, directions: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Blended spectral radiance [W m^-2 sr^-1 nm^-1], shape (..., n_wavelengths)."""
        wl = as_wavelengths(wavelengths)
        w = self.weight
        out = w * self.overcast_luminance(directions)[..., None] * np.full(wl.shape, self._flat_unit)
        if w < 1.0:
            out = out + (1.0 - w) * self.clear.spectral_radiance(directions, wl)
        return out

    def sun_spectral_radiance(self, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Preetham's solar disc radiance times (1 - w) [W m^-2 sr^-1 nm^-1]."""
        wl = as_wavelengths(wavelengths)
        if self.weight >= 1.0:
            return np.zeros(wl.shape)
        return (1.0 - self.weight) * self.clear.sun_spectral_radiance(wl)
