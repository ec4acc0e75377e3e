"""Turbidity relations: Angstrom coefficients (Preetham 1999, A.1) and the meteorological range (Sec. 2.1).

Reference: [Preetham1999]. The
Angstrom beta of A.1 is written once here (:func:`angstrom_beta`) and used by the Preetham sunlight and by
:meth:`skyscatter.atmosphere.AtmosphereParameters.from_turbidity`.

Turbidity T is the ratio of the vertical optical thickness of the haze-plus-molecule atmosphere to that of the
molecules alone, T = (t_m + t_h) / t_m (Preetham 1999, Sec. 2.1, after McCartney 1976), taken at 550 nm.

Meteorological range. Preetham's Fig. 3 plots R_m against T from McCartney's data but prints no formula. Here
R_m is computed with Koschmieder's relation (Koschmieder 1924, as presented by McCartney 1976), the distance
at which the contrast of a black target against the horizon sky falls to the threshold epsilon = 0.02 that the
paper quotes:

    R_m = ln(1 / epsilon) / beta_ext(550 nm) = 3.912 / (beta_m(550) + beta_p(550, T))

with beta_m the Rayleigh coefficient and beta_p the Mie (haze) coefficient of A.3 at sea level (haze
absorption neglected, as in the paper's scattering-only haze). beta_p is linear in T, so the relation
inverts in closed form. Pure air (T = 1) gives 280 km, T = 2 gives 42 km and T = 10 gives 5.4 km. In the
International Visibility Code classes (as tabulated by McCartney 1976) that is: "exceptionally clear" (> 50
km) for T < 1.8, "very clear" (20-50 km) for T = 1.8-3.3, "clear" (10-20 km) for T = 3.3-5.8, "light haze"
(4-10 km) for T = 5.8-13 and "haze" (2-4 km) for T = 13-26.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from .mie import mie_total_scattering
from .rayleigh import rayleigh_total_scattering

__all__ = [
    "ANGSTROM_ALPHA",
    "KOSCHMIEDER_CONSTANT",
    "angstrom_beta",
    "angstrom_beta_from_optical_depth",
    "meteorological_range",
    "turbidity_from_meteorological_range",
]

#: Angstrom wavelength exponent alpha [-] of Preetham (1999), A.1 ("as originally suggested by Angstrom").
ANGSTROM_ALPHA = 1.3
#: ln(1 / 0.02): Koschmieder's constant for the 2 % contrast threshold [-].
KOSCHMIEDER_CONSTANT = float(np.log(1.0 / 0.02))
_REFERENCE_WAVELENGTH = 550.0


def angstrom_beta_from_optical_depth(optical_depth: float, alpha: float = ANGSTROM_ALPHA,
                                     wavelength: float = _REFERENCE_WAVELENGTH) -> float:
    """Angstrom's beta [-] for a vertical aerosol optical depth ``tau`` at ``wavelength`` [nm] (default 550).

    Angstrom's law ``tau(lambda) = beta (lambda / 1 um)^-alpha`` ([Angstrom1929])
    inverted: ``beta = tau (lambda / 1 um)^alpha``.
    """
    return float(optical_depth) * (float(wavelength) / 1000.0) ** float(alpha)


def _turbidity_array(turbidity: ArrayLike) -> NDArray[np.float64]:
    t = np.asarray(turbidity, dtype=float)
    if np.any(~np.isfinite(t)) or np.any(t < 1.0):
        raise InvalidParameterError("turbidity must be finite and >= 1 (1 = pure molecular air)")
    return t


def angstrom_beta(turbidity: ArrayLike) -> NDArray[np.float64] | float:
    """Angstrom turbidity coefficient beta = 0.04608 T - 0.04586 [-] (Preetham 1999, A.1).

    The aerosol optical depth at wavelength lambda [um] is ``beta * lambda^-alpha`` with
    :data:`ANGSTROM_ALPHA` = 1.3.

    Parameters
    ----------
    turbidity : array_like
        Turbidity T >= 1 [-].
    """
    t = _turbidity_array(turbidity)
    beta = 0.04608 * t - 0.04586
    return float(beta) if beta.ndim == 0 else beta


def _coefficients_550() -> tuple[float, float, float]:
    """beta_m(550) [m^-1] and the linear form beta_p(550, T) = a T + b [m^-1]."""
    beta_m = float(rayleigh_total_scattering([_REFERENCE_WAVELENGTH])[0])
    p1 = float(mie_total_scattering([_REFERENCE_WAVELENGTH], 1.0)[0])
    p2 = float(mie_total_scattering([_REFERENCE_WAVELENGTH], 2.0)[0])
    return beta_m, p2 - p1, 2.0 * p1 - p2


def meteorological_range(turbidity: ArrayLike) -> NDArray[np.float64] | float:
    """Meteorological range R_m [m] for a turbidity (Koschmieder relation, module docstring).

    Parameters
    ----------
    turbidity : array_like
        Turbidity T >= 1 [-].

    Returns
    -------
    float or ndarray
        R_m [m], same shape as ``turbidity``.
    """
    t = _turbidity_array(turbidity)
    beta_m, a, b = _coefficients_550()
    r = KOSCHMIEDER_CONSTANT / (beta_m + a * t + b)
    return float(r) if r.ndim == 0 else r


def turbidity_from_meteorological_range(meteorological_range_m: ArrayLike) -> NDArray[np.float64] | float:
    """Turbidity T [-] that gives a meteorological range [m]; inverse of :func:`meteorological_range`.

    Parameters
    ----------
    meteorological_range_m : array_like
        Meteorological range (visibility) R_m [m]; at most the pure-air range (about 280 km, T = 1).
    """
    r = np.asarray(meteorological_range_m, dtype=float)
    r_max = meteorological_range(1.0)
    if np.any(~np.isfinite(r)) or np.any(r <= 0.0) or np.any(r > r_max * (1.0 + 1e-9)):
        raise InvalidParameterError(
            f"meteorological range must be in (0, {r_max:.0f}] m; "
            "the upper bound is pure molecular air (T = 1)"
        )
    beta_m, a, b = _coefficients_550()
    t = np.maximum((KOSCHMIEDER_CONSTANT / r - beta_m - b) / a, 1.0)
    return float(t) if t.ndim == 0 else t
