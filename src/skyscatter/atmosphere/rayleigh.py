"""Rayleigh scattering by air molecules: one formula, one set of physical constants, and Preetham's A.3.

The scattering coefficient of a gas of N molecules per m^3 with refractive index n is

    beta(lambda) = 8 pi^3 (n^2 - 1)^2 / (3 N lambda^4) * F_K,     F_K = (6 + 3 p_n) / (6 - 7 p_n)

([Penndorf1957]; [Bodhaine1999] Eqs. 2 and 3 with the King factor F_K of the
depolarisation p_n), and the angular coefficient is beta times the Rayleigh phase function
(:func:`skyscatter.atmosphere.phase.rayleigh_phase`). Wavelengths are taken in nm; coefficients are in m^-1.

Constants (the one set for every model that describes air from physics: the path tracer, the physical
spectrum of the precomputed model):

* :data:`STANDARD_AIR_NUMBER_DENSITY` N_s = 2.546899e25 m^-3, molecules of standard air at 288.15 K and
  1013.25 hPa (Bodhaine et al. 1999, Sec. 2; = p / (k T) with the CODATA Boltzmann constant).
* refractive index of standard air (300 ppm CO2) n_s(lambda) of [PeckReeder1972], as
  Bodhaine et al. Eq. 4: :func:`refractive_index_standard_air`.
  (n_s - 1 = 2.778e-4 at 550 nm.) The formula uses n^2 - 1, not its approximation 2 (n - 1), with which
  beta would be 2.8e-4 (relative) smaller.
* :data:`DEPOLARISATION` p_n = 0.035 (Penndorf 1957, the value of Preetham et al. 1999, A.3): King factor
  1.0608. Bodhaine et al. prefer Bates' (1984) wavelength-dependent King factor, 1.0485 at 550 nm, 1.2 %
  lower; 0.035 is kept as the one value so that the Preetham model and the physical spectrum share it.

Preetham, Shirley & Smits ([Preetham1999] Appendix A.3) evaluate the same formula with a wavelength-independent
n = 1.0003 and N = 2.545e25 m^-3 (:data:`AIR_REFRACTIVE_INDEX_PREETHAM1999`, :data:`AIR_NUMBER_DENSITY_PREETHAM1999`).
Those are part of their model (the sky and aerial-perspective fits were made with them) and Bruneton's (2017) default
coefficients
(5.802, 13.558, 33.100)e-6 m^-1 reproduce them to 0.05 %, so the Preetham functions keep them. They give
12.7 % (400 nm) to 18.4 % (700 nm) more scattering than standard air: n = 1.0003 overstates n - 1 at 550 nm
by 8 %, squared 16.7 %, and a constant n has no dispersion; N differs by -0.075 % (2.545e25 is the same
288 K density, rounded). The course notes print p_n = 0.0035; the paper's 0.035 is the standard value (the
misprint would lose about 11 % of the scattering, see the seeds' errata).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ._common import positive_finite, scattering_angles, wavelengths_m
from .phase import rayleigh_phase

__all__ = [
    "AIR_NUMBER_DENSITY",
    "AIR_NUMBER_DENSITY_PREETHAM1999",
    "AIR_REFRACTIVE_INDEX",
    "AIR_REFRACTIVE_INDEX_PREETHAM1999",
    "DEPOLARISATION",
    "STANDARD_AIR_NUMBER_DENSITY",
    "king_factor",
    "rayleigh_angular_scattering",
    "rayleigh_angular_scattering_preetham1999",
    "rayleigh_scattering_bodhaine1999",
    "rayleigh_total_scattering",
    "rayleigh_total_scattering_preetham1999",
    "refractive_index_standard_air",
]

#: Molecules per m^3 of standard air, 288.15 K and 1013.25 hPa [m^-3] (Bodhaine et al. 1999).
STANDARD_AIR_NUMBER_DENSITY = 2.546899e25
#: Depolarisation factor of air [-] (Preetham 1999, A.3; not the course notes' 0.0035). King factor 1.0608.
DEPOLARISATION = 0.035
#: Wavelength-independent refractive index of air of Preetham (1999), A.3 [-].
AIR_REFRACTIVE_INDEX_PREETHAM1999 = 1.0003
#: Molecular number density at sea level of Preetham (1999), A.3 [m^-3].
AIR_NUMBER_DENSITY_PREETHAM1999 = 2.545e25
#: Former names of the Preetham (1999) A.3 constants (kept as aliases).
AIR_REFRACTIVE_INDEX = AIR_REFRACTIVE_INDEX_PREETHAM1999
AIR_NUMBER_DENSITY = AIR_NUMBER_DENSITY_PREETHAM1999


def king_factor(depolarisation: float = DEPOLARISATION) -> float:
    """King correction factor ``(6 + 3 p_n) / (6 - 7 p_n)`` [-] for molecular anisotropy (Preetham 1999, A.3).

    Parameters
    ----------
    depolarisation : float
        Depolarisation factor p_n [-], in [0, 6/7); default 0.035 gives about 1.061.
    """
    try:
        p = float(depolarisation)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"depolarisation factor must be a number; got {depolarisation!r}") from None
    if not (np.isfinite(p) and 0.0 <= p < 6.0 / 7.0):
        raise InvalidParameterError(f"depolarisation factor must be in [0, 6/7); got {depolarisation!r}")
    return (6.0 + 3.0 * p) / (6.0 - 7.0 * p)


def _rayleigh_coefficient(lam_m, n, number_density, king):
    """The formula of the module docstring: beta [m^-1] for wavelengths [m] and refractive index n."""
    return 8.0 * np.pi**3 * (n * n - 1.0) ** 2 / (3.0 * number_density * lam_m**4) * king


def refractive_index_standard_air(wavelengths: ArrayLike) -> NDArray[np.float64]:
    """Refractive index of standard air (288.15 K, 1013.25 hPa, 300 ppm CO2) [-], Peck & Reeder (1972).

    ``(n - 1) 1e8 = 8060.51 + 2480990 / (132.274 - s^2) + 17455.7 / (39.32957 - s^2)``, ``s = 1 / lambda``
    [um^-1] (Bodhaine et al. 1999, Eq. 4).

    Parameters
    ----------
    wavelengths : array_like, shape (n,)
        Wavelengths [nm] (the fit covers 230 nm - 1.69 um).
    """
    wl, _ = wavelengths_m(wavelengths)
    s2 = (wl * 1e-3) ** -2
    return 1.0 + 1e-8 * (8060.51 + 2480990.0 / (132.274 - s2) + 17455.7 / (39.32957 - s2))


def rayleigh_scattering_bodhaine1999(
    wavelengths: ArrayLike, *, depolarisation: float = DEPOLARISATION
) -> NDArray[np.float64]:
    """Rayleigh scattering coefficient of standard air [m^-1] from the physics (module docstring).

    Standard-air density :data:`STANDARD_AIR_NUMBER_DENSITY`, Peck & Reeder's refractive index and the King
    factor of ``depolarisation`` (Bodhaine et al. 1999, Eqs. 2-4). About 1.162e-5 m^-1 at 550 nm.

    Parameters
    ----------
    wavelengths : array_like, shape (n,)
        Wavelengths [nm].
    depolarisation : float
        Depolarisation factor p_n [-].
    """
    _, lam = wavelengths_m(wavelengths)
    n = refractive_index_standard_air(wavelengths)
    return _rayleigh_coefficient(lam, n, STANDARD_AIR_NUMBER_DENSITY, king_factor(depolarisation))


def rayleigh_total_scattering_preetham1999(
    wavelengths: ArrayLike,
    *,
    refractive_index: float = AIR_REFRACTIVE_INDEX_PREETHAM1999,
    number_density: float = AIR_NUMBER_DENSITY_PREETHAM1999,
    depolarisation: float = DEPOLARISATION,
) -> NDArray[np.float64]:
    """Total Rayleigh scattering coefficient beta_m [m^-1] at sea level (Preetham 1999, A.3).

    Parameters
    ----------
    wavelengths : array_like, shape (n,)
        Wavelengths [nm].
    refractive_index : float
        Refractive index of air n [-] (> 1), wavelength independent.
    number_density : float
        Molecular number density N [m^-3].
    depolarisation : float
        Depolarisation factor p_n [-].

    Returns
    -------
    ndarray, shape (n,)
        beta_m [m^-1]; about 1.356e-5 m^-1 at 550 nm with the defaults (16.7 % above standard air, see the
        module docstring).
    """
    _, lam = wavelengths_m(wavelengths)
    n = float(refractive_index)
    if not (np.isfinite(n) and n > 1.0):
        raise InvalidParameterError(f"refractive_index must be finite and > 1; got {refractive_index!r}")
    big_n = positive_finite("number_density [m^-3]", number_density)
    return _rayleigh_coefficient(lam, n, big_n, king_factor(depolarisation))


def rayleigh_angular_scattering_preetham1999(
    theta: ArrayLike,
    wavelengths: ArrayLike,
    *,
    refractive_index: float = AIR_REFRACTIVE_INDEX_PREETHAM1999,
    number_density: float = AIR_NUMBER_DENSITY_PREETHAM1999,
    depolarisation: float = DEPOLARISATION,
) -> NDArray[np.float64]:
    """Angular Rayleigh scattering coefficient beta_m(theta) [m^-1 sr^-1] (Preetham 1999, A.3).

    Equal to the total coefficient times :func:`~skyscatter.atmosphere.phase.rayleigh_phase`, so it integrates
    to :func:`rayleigh_total_scattering_preetham1999` over the sphere.

    Parameters
    ----------
    theta : array_like, shape (...)
        Scattering angle [rad], in [0, pi].
    wavelengths : array_like, shape (n,)
        Wavelengths [nm].
    refractive_index, number_density, depolarisation : float
        As in :func:`rayleigh_total_scattering_preetham1999`.

    Returns
    -------
    ndarray, shape (..., n)
    """
    th = scattering_angles(theta)
    total = rayleigh_total_scattering_preetham1999(
        wavelengths, refractive_index=refractive_index, number_density=number_density,
        depolarisation=depolarisation,
    )
    return rayleigh_phase(np.cos(th))[..., None] * total


#: Former names (kept as aliases) of the Preetham (1999) A.3 coefficients.
rayleigh_total_scattering = rayleigh_total_scattering_preetham1999
rayleigh_angular_scattering = rayleigh_angular_scattering_preetham1999
