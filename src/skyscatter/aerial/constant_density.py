"""Constant-density aerial perspective (Preetham, "Modeling Skylight and Aerial Perspective", course notes).

For landscape views the rays stay close to the ground, so the notes take the density of the medium as
constant along the ray (the optical length of a path equals its length) and keep only sunlight as the source
of in-scattering:

    f = exp(-beta s),      L_in = E^s beta(omega, omega^s) / beta (1 - exp(-beta s))

with E^s the sun's irradiance at the ground and beta(omega, omega^s) the angular scattering coefficient for
the angle between the view and the sun. The notes leave the extension to several kinds of particles "as an
exercise"; for haze (1) and molecules (2), single scattering gives

    tau = exp(-(beta_1 + beta_2) s),   L_in = (S_1 + S_2) / (beta_1 + beta_2) (1 - tau)

with ``S_i = E^s beta_i(omega, omega^s)`` (and, optionally, the sky's share of S^0, as in Preetham 1999).
A sky without a sun (the CIE overcast sky) has no E^s: with sunlight only its haze would be black, so for such
skies the sky's share is included by default.
Here the "constant" density is the one at the observer's height, ``beta_i = beta_i^0 exp(-alpha_i h0)`` with
the A.4 decay constants, so the model agrees with :class:`PreethamAerialPerspective` for horizontal rays
(test_aerial.py checks this).

Reference: [Preetham1999].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere import mie_total_scattering, rayleigh_total_scattering
from ..errors import InvalidParameterError
from ..sky.base import SkyModel
from .base import AerialPerspective, check_path, check_rays
from .integrals import ALPHA_HAZE, ALPHA_MOLECULES
from .preetham import resolve_turbidity
from .scattering import ScatteringTable

__all__ = ["ConstantDensityAerialPerspective"]


class ConstantDensityAerialPerspective(AerialPerspective):
    """Aerial perspective with the density at the observer's height all along the ray.

    Parameters
    ----------
    sky : SkyModel
        Sun (and optionally sky) providing the in-scattered light.
    turbidity : float, optional
        Haze turbidity [-]; default ``sky.turbidity``.
    include_sky : bool, optional
        Add the sky's in-scattering. Default: False (sunlight only, as in the course notes) for a sky with a
        sun; True for a sky without one, whose haze would otherwise be black.
    alpha_haze, alpha_molecules : float
        Decay constants [m^-1] that set the density at the observer's height (positive).

    Raises
    ------
    InvalidParameterError
        A bad turbidity or decay constant, or ``include_sky=False`` for a sky without a sun (no light
        would be scattered towards the viewer).
    """

    def __init__(self, sky: SkyModel, *, turbidity: float | None = None, include_sky: bool | None = None,
                 alpha_haze: float = ALPHA_HAZE, alpha_molecules: float = ALPHA_MOLECULES) -> None:
        for name, value in (("alpha_haze", alpha_haze), ("alpha_molecules", alpha_molecules)):
            if not (isinstance(value, int | float | np.number) and np.isfinite(value) and value > 0):
                raise InvalidParameterError(f"{name} must be a positive decay constant [m^-1]; got {value!r}")
        self.sky = sky
        self.turbidity = resolve_turbidity(sky, turbidity)
        sunny = sky.sun is not None
        if include_sky is None:
            include_sky = not sunny
        elif not include_sky and not sunny:
            raise InvalidParameterError(
                f"{type(sky).__name__} has no sun, so with include_sky=False nothing would light the haze (it "
                "would render black); use include_sky=True or leave it at the default"
            )
        self.include_sky = bool(include_sky)
        self.alpha_haze = float(alpha_haze)
        self.alpha_molecules = float(alpha_molecules)
        self._tables: dict[tuple[float, ...], ScatteringTable] = {}

    def __repr__(self) -> str:
        return f"ConstantDensityAerialPerspective({self.sky!r}, turbidity={self.turbidity:g})"

    def _coefficients(self, h: NDArray, wl: NDArray) -> tuple[NDArray, NDArray]:
        b1 = mie_total_scattering(wl, self.turbidity) * np.exp(-self.alpha_haze * h)[..., None]
        b2 = rayleigh_total_scattering(wl) * np.exp(-self.alpha_molecules * h)[..., None]
        return b1, b2

    def transmittance(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """``exp(-(beta_1 + beta_2) s)``, shape (..., n_wavelengths); arguments as in the protocol."""
        d, s, h, wl = check_path(directions, distances, observer_height, wavelengths)
        b1, b2 = self._coefficients(h, wl)
        return np.exp(-(b1 + b2) * s[..., None])

    def evaluate_rays(self, origins: ArrayLike, directions: ArrayLike, distances: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(tau, L_in [W m^-2 sr^-1 nm^-1]) of paths from ``origins`` (ENU [m]; only their height ``z``
        matters), each (..., n_wavelengths)."""
        o, d, s, wl = check_rays(origins, directions, distances, wavelengths)
        h = o[..., 2]
        key = tuple(wl.tolist())
        if key not in self._tables:
            self._tables[key] = ScatteringTable(self.sky, self.turbidity, wl, include_sky=self.include_sky)
        s1, s2 = self._tables[key].lookup(d)
        b1, b2 = self._coefficients(h, wl)
        beta = b1 + b2
        tau = np.exp(-beta * s[..., None])
        h1 = np.exp(-self.alpha_haze * h)[..., None]
        h2 = np.exp(-self.alpha_molecules * h)[..., None]
        return tau, (s1 * h1 + s2 * h2) / beta * (1.0 - tau)
