"""Analytic aerial perspective of Preetham, Shirley & Smits (1999), Sec. 4 and Appendix A.4.

``L(s) = L_0 tau + L_in`` with the two-species exponential atmosphere: tau from Eq. 7,
``L_in = S_1^0 I_1 + S_2^0 I_2`` (Eq. 8), S^0 precomputed from the sun and sky
(:class:`~skyscatter.aerial.scattering.ScatteringTable`) and I from :mod:`skyscatter.aerial.integrals`.
Scattering coefficients: Rayleigh for molecules and Mie with the Table 1/Table 2 data for haze (A.3), via
:mod:`skyscatter.atmosphere`.

Reference: [Preetham1999].
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..atmosphere import mie_total_scattering, rayleigh_total_scattering
from ..errors import InvalidParameterError
from ..sky.base import SkyModel
from ..validation import whole_number
from .base import AerialPerspective, check_path, check_rays
from .integrals import ALPHA_HAZE, ALPHA_MOLECULES, extinction, in_scattering_integrals
from .scattering import ScatteringTable

__all__ = ["PreethamAerialPerspective", "resolve_turbidity"]

_METHODS = {"analytic": "analytic", "numeric": "quadrature"}


def resolve_turbidity(sky: SkyModel, turbidity: float | None) -> float:
    """The haze turbidity: ``turbidity`` if given, else ``sky.turbidity``; raises if neither exists."""
    if turbidity is None:
        turbidity = sky.turbidity
        if turbidity is None:
            raise InvalidParameterError(
                f"{type(sky).__name__} has no turbidity; pass turbidity= (T >= 1) for the haze of the aerial "
                "perspective"
            )
    try:
        t = float(turbidity)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"turbidity must be a number >= 1; got {turbidity!r}") from None
    if not (np.isfinite(t) and t >= 1.0):
        raise InvalidParameterError(f"turbidity must be finite and >= 1; got {turbidity!r}")
    return t


class PreethamAerialPerspective(AerialPerspective):
    """Preetham et al. 1999 aerial perspective for a sky (and its sun).

    Parameters
    ----------
    sky : SkyModel
        Source of the in-scattered light: its sky radiance is integrated over the hemisphere and, when it
        has a sun, the solar disc enters as a delta (Sec. 4.2). Any skyscatter sky works (Preetham, CIE, ...).
    method : {"analytic", "numeric"}
        How the integrals I_1, I_2 are computed: ``analytic`` is the paper's closed form (Eq. 10 near the
        horizon, the Hermite-cubic Eq. 11 / A.4 elsewhere) applied piecewise along the path (see
        ``segments``); ``numeric`` is Gauss-Legendre quadrature, the reference.
    turbidity : float, optional
        Turbidity of the haze [-]; default ``sky.turbidity`` (required for skies without one).
    segments : "auto" or int
        Pieces of the analytic form. ``1`` is the paper as published (accurate only for short or clear
        paths, see ``docs/aerial.md``); ``"auto"`` (default) keeps each piece below one optical depth.
    include_sun, include_sky : bool
        Sources of in-scattering (both by default).
    alpha_haze, alpha_molecules : float
        Density decay constants [m^-1] (A.4: 0.8333 and 0.1136 km^-1).

    Notes
    -----
    Flat earth; the sun and sky radiance are taken as independent of height (Sec. 4.2). S^0 tables are
    built per wavelength grid on first use and cached on the instance.
    """

    def __init__(self, sky: SkyModel, *, method: str = "analytic", turbidity: float | None = None,
                 segments: int | str = "auto", include_sun: bool = True, include_sky: bool = True,
                 alpha_haze: float = ALPHA_HAZE, alpha_molecules: float = ALPHA_MOLECULES) -> None:
        if method not in _METHODS:
            raise InvalidParameterError(f"method must be 'analytic' or 'numeric'; got {method!r}")
        for name, value in (("alpha_haze", alpha_haze), ("alpha_molecules", alpha_molecules)):
            if not (np.isfinite(value) and value > 0):
                raise InvalidParameterError(f"{name} must be a positive decay constant [m^-1]; got {value!r}")
        self.sky = sky
        self.method = method
        self.turbidity = resolve_turbidity(sky, turbidity)
        if isinstance(segments, str) and segments != "auto":
            raise InvalidParameterError(f"segments must be 'auto' or a whole number in [1, 10000]; got {segments!r}")
        self.segments = segments if isinstance(segments, str) else whole_number("segments ('auto' or)", segments, 1,
                                                                                  10_000)
        self.include_sun = include_sun
        self.include_sky = include_sky
        self.alpha_haze = float(alpha_haze)
        self.alpha_molecules = float(alpha_molecules)
        self._tables: dict[tuple[float, ...], ScatteringTable] = {}

    def __repr__(self) -> str:
        return f"PreethamAerialPerspective({self.sky!r}, method={self.method!r}, turbidity={self.turbidity:g})"

    def scattering_coefficients(self, wavelengths: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Sea-level total scattering coefficients (beta_haze, beta_molecules) [m^-1] (A.3), each (n,)."""
        return mie_total_scattering(wavelengths, self.turbidity), rayleigh_total_scattering(wavelengths)

    def table(self, wavelengths: ArrayLike) -> ScatteringTable:
        """The S^0 table for a wavelength grid [nm] (built on first use)."""
        wl = np.asarray(wavelengths, dtype=float)
        key = tuple(wl.tolist())
        if key not in self._tables:
            self._tables[key] = ScatteringTable(self.sky, self.turbidity, wl, include_sun=self.include_sun,
                                                include_sky=self.include_sky)
        return self._tables[key]

    def transmittance(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Extinction factor tau (Eq. 7) of paths, shape (..., n_wavelengths).

        Parameters
        ----------
        directions : array_like, shape (..., 3)
            View directions from the observer to the object (ENU).
        distances : array_like, shape (...)
            Distances to the object [m].
        observer_height : array_like
            Observer height [m above sea level], broadcast with the distances.
        wavelengths : array_like, optional
            Wavelengths [nm].
        """
        d, s, h, wl = check_path(directions, distances, observer_height, wavelengths)
        b1, b2 = self.scattering_coefficients(wl)
        return extinction(d[..., 2], s, h, b1, b2, alpha_haze=self.alpha_haze, alpha_molecules=self.alpha_molecules)

    def integrals(self, directions: ArrayLike, distances: ArrayLike, observer_height: ArrayLike,
                  wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(I_1, I_2) [m] of Eq. 8 with this model's method, each (..., n_wavelengths)."""
        d, s, h, wl = check_path(directions, distances, observer_height, wavelengths)
        b1, b2 = self.scattering_coefficients(wl)
        return in_scattering_integrals(d[..., 2], s, h, b1, b2, method=_METHODS[self.method],
                                       alpha_haze=self.alpha_haze, alpha_molecules=self.alpha_molecules,
                                       segments=self.segments)

    def evaluate_rays(self, origins: ArrayLike, directions: ArrayLike, distances: ArrayLike,
                      wavelengths: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Extinction tau (Eq. 7) and in-scattered spectral radiance L_in [W m^-2 sr^-1 nm^-1] (Eq. 8) of
        paths from ``origins`` (ENU [m]; the flat atmosphere depends on their height ``z`` only), each
        (..., n_wavelengths); other parameters as in :meth:`transmittance`."""
        o, d, s, wl = check_rays(origins, directions, distances, wavelengths)
        h = o[..., 2]
        b1, b2 = self.scattering_coefficients(wl)
        i1, i2, tau = in_scattering_integrals(d[..., 2], s, h, b1, b2, method=_METHODS[self.method],
                                              alpha_haze=self.alpha_haze, alpha_molecules=self.alpha_molecules,
                                              segments=self.segments, return_transmittance=True)
        return tau, self.table(wl).inscattered(d, i1, i2)
