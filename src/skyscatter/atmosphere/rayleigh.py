"""Rayleigh scattering by air molecules, Preetham, Shirley & Smits (1999) Appendix A.3.

    beta_m(theta) = pi^2 (n^2 - 1)^2 / (2 N lambda^4) * (6 + 3 p_n) / (6 - 7 p_n) * (1 + cos^2 theta)
    beta_m        = 8 pi^3 (n^2 - 1)^2 / (3 N lambda^4) * (6 + 3 p_n) / (6 - 7 p_n)

with n = 1.0003 (refractive index of air in the visible), N = 2.545e25 m^-3 (molecular number density at sea
level) and p_n = 0.035 (depolarisation factor). The course notes print p_n = 0.0035; the paper's 0.035 is the
standard value (King factor about 1.061; the misprint would lose about 11 % of the scattering, see the seeds'
errata). Wavelengths are taken in nm and converted to metres; coefficients are in m^-1 (m^-1 sr^-1 for the
angular coefficient).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ._common import positive_finite, scattering_angles, wavelengths_m
from .phase import rayleigh_phase

__all__ = [
    "AIR_NUMBER_DENSITY",
    "AIR_REFRACTIVE_INDEX",
    "DEPOLARISATION",
    "king_factor",
    "rayleigh_angular_scattering",
    "rayleigh_total_scattering",
]

#: Refractive index of air in the visible spectrum [-] (Preetham 1999, A.3).
AIR_REFRACTIVE_INDEX = 1.0003
#: Number of molecules per unit volume of air at sea level [m^-3] (Preetham 1999, A.3).
AIR_NUMBER_DENSITY = 2.545e25
#: Depolarisation factor of air [-] (Preetham 1999, A.3; not the course notes' 0.0035).
DEPOLARISATION = 0.035


def king_factor(depolarisation: float = DEPOLARISATION) -> float:
    """King correction factor ``(6 + 3 p_n) / (6 - 7 p_n)`` [-] for molecular anisotropy (Preetham 1999, A.3).

    Parameters
    ----------
    depolarisation : float
        Depolarisation factor p_n [-], in [0, 6/7); default 0.035 gives about 1.061.
    """
    p = float(depolarisation)
    if not (np.isfinite(p) and 0.0 <= p < 6.0 / 7.0):
        raise InvalidParameterError(f"depolarisation factor must be in [0, 6/7); got {depolarisation!r}")
    return (6.0 + 3.0 * p) / (6.0 - 7.0 * p)


def rayleigh_total_scattering(
    wavelengths: ArrayLike,
    *,
    refractive_index: float = AIR_REFRACTIVE_INDEX,
    number_density: float = AIR_NUMBER_DENSITY,
    depolarisation: float = DEPOLARISATION,
) -> NDArray[np.float64]:
    """Total Rayleigh scattering coefficient beta_m [m^-1] at sea level (Preetham 1999, A.3).

    Parameters
    ----------
    wavelengths : array_like, shape (n,)
        Wavelengths [nm].
    refractive_index : float
        Refractive index of air n [-] (> 1).
    number_density : float
        Molecular number density N [m^-3].
    depolarisation : float
        Depolarisation factor p_n [-].

    Returns
    -------
    ndarray, shape (n,)
        beta_m [m^-1]; about 1.36e-5 m^-1 at 550 nm with the defaults.
    """
    _, lam = wavelengths_m(wavelengths)
    n = float(refractive_index)
    if not (np.isfinite(n) and n > 1.0):
        raise InvalidParameterError(f"refractive_index must be finite and > 1; got {refractive_index!r}")
    big_n = positive_finite("number_density [m^-3]", number_density)
    return 8.0 * np.pi**3 * (n * n - 1.0) ** 2 / (3.0 * big_n * lam**4) * king_factor(depolarisation)


def rayleigh_angular_scattering(
    theta: ArrayLike,
    wavelengths: ArrayLike,
    *,
    refractive_index: float = AIR_REFRACTIVE_INDEX,
    number_density: float = AIR_NUMBER_DENSITY,
    depolarisation: float = DEPOLARISATION,
) -> NDArray[np.float64]:
    """Angular Rayleigh scattering coefficient beta_m(theta) [m^-1 sr^-1] (Preetham 1999, A.3).

    Equal to the total coefficient times :func:`~skyscatter.atmosphere.phase.rayleigh_phase`, so it integrates
    to :func:`rayleigh_total_scattering` over the sphere.

    Parameters
    ----------
    theta : array_like, shape (...)
        Scattering angle [rad], in [0, pi].
    wavelengths : array_like, shape (n,)
        Wavelengths [nm].
    refractive_index, number_density, depolarisation : float
        As in :func:`rayleigh_total_scattering`.

    Returns
    -------
    ndarray, shape (..., n)
    """
    th = scattering_angles(theta)
    total = rayleigh_total_scattering(
        wavelengths, refractive_index=refractive_index, number_density=number_density,
        depolarisation=depolarisation,
    )
    return rayleigh_phase(np.cos(th))[..., None] * total
