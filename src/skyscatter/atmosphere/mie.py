"""Mie scattering by haze, [Preetham1999] Appendix A.3, Tables 1 and 2.

For a Junge size distribution with exponent v = 4 (the paper's sky model):

    beta_p(theta) = 0.434 c (2 pi / lambda)^(v - 2) * eta(theta, lambda) / 2      [m^-1 sr^-1]
    beta_p        = 0.434 c pi (2 pi / lambda)^(v - 2) * K(lambda)                 [m^-1]
    c             = (0.6544 T - 0.6510) * 1e-16                                    (concentration factor)

eta(theta, lambda) is Table 1 (after [Bullrich1964]) and K(lambda) the K column of Table 2, both shipped as CSV
files in ``skyscatter/data``.

Units of c (why there is a factor 0.01). Read literally with lambda in metres, the formulas give
beta_p(550 nm, T = 2) = 7.9e-3 m^-1, a meteorological range of about 500 m: fog, not a clear day. The formula
is McCartney's (1976, Eq. 6-30) for a Junge distribution dN/dlog10(r) = c r^-v, whose concentration factor is
in cgs units, cm^(v-3) (number density per cm^3, radius in cm). Converting c to SI multiplies it by
0.01^(v-3). The authors' own implementation that accompanied the paper (B. Smits, 1999, ``RiSunSky.C``,
``CreateConstants``) applies exactly this factor ("unit correction for c") to both the total and the angular
coefficient. skyscatter does the same: beta_p(550 nm, T = 2) = 7.9e-5 m^-1. Independent checks (in the
test suite): the Angstrom relation of A.1 (beta = 0.04608 T - 0.04586, alpha = 1.3) gives an
aerosol optical depth of 0.101 at 550 nm for T = 2, i.e. a sea-level coefficient of 8.4e-5 m^-1 for the
paper's haze scale height of 1.2 km (alpha_haze = 0.8333 km^-1, A.4); the turbidity definition
T = (t_m + t_h) / t_m with the Rayleigh coefficient and an 8.8 km molecular scale height (A.4) gives
9.9e-5 m^-1.

Interpolation. eta is interpolated linearly in log(eta) over theta (the forward peak falls by a factor 30
from 1 to 90 deg) and linearly over wavelength; below 1 deg it is held at its 1-deg value, outside 400-850 nm
at the nearest column. K is interpolated linearly and held constant outside 380-780 nm (it varies by 6 %
over the whole table).

Consistency of the two tables. The coefficients require integral of beta_p(theta) over the sphere = beta_p,
i.e. K = integral_0^pi eta sin(theta) dtheta. With Table 1 interpolated as above that integral is 1.005 K
at 400-780 nm (:func:`eta_integral_ratio`; linear instead of log-linear interpolation in theta gives 1.07 K):
the two published tables agree to 0.5 %, which also confirms their transcription. :func:`mie_phase_function`
offers eta normalised to exactly 1 over the sphere.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ._common import scattering_angles, wavelengths_m
from .tables import load_table, tabulated

__all__ = [
    "JUNGE_EXPONENT",
    "eta_integral_ratio",
    "haze_concentration",
    "mie_angular_scattering",
    "mie_k",
    "mie_eta",
    "mie_phase_function",
    "mie_total_scattering",
]

#: Junge exponent v of the haze size distribution used by Preetham (1999) [-]; Tables 1 and 2 are for v = 4.
JUNGE_EXPONENT = 4.0
_ETA_TABLE = "preetham1999_table1_mie_eta"
_ETA_WAVELENGTHS = np.array([400.0, 450.0, 550.0, 650.0, 850.0])
# c is in cgs units cm^(v-3); this converts it to m^(v-3) (see the module docstring).
_C_TO_SI = 0.01 ** (JUNGE_EXPONENT - 3.0)


def _turbidity(turbidity: float) -> float:
    try:
        t = float(turbidity)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"turbidity must be a number >= 1; got {turbidity!r}") from None
    if not (np.isfinite(t) and t >= 1.0):
        raise InvalidParameterError(
            f"turbidity must be finite and >= 1 (1 = pure molecular air, T = (t_m + t_h) / t_m); "
            f"got {turbidity!r}"
        )
    return t


def haze_concentration(turbidity: float) -> float:
    """Concentration factor c = (0.6544 T - 0.6510) x 1e-16 (Preetham 1999, A.3) [cm^(v-3), cm for v = 4].

    The value is in McCartney's cgs units, as published; the scattering functions convert it to SI.

    Parameters
    ----------
    turbidity : float
        Turbidity T >= 1 [-].
    """
    t = _turbidity(turbidity)
    return (0.6544 * t - 0.6510) * 1e-16


def mie_k(wavelengths: ArrayLike) -> NDArray[np.float64]:
    """K(lambda) for v = 4 (Preetham 1999, Table 2) [-], linear in wavelength, held outside 380-780 nm."""
    wl, _ = wavelengths_m(wavelengths)
    x, k = tabulated("preetham1999_table2", "K")
    return np.interp(wl, x, k)


@lru_cache(maxsize=1)
def _eta_log_table() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    table = load_table(_ETA_TABLE)
    columns = [f"eta_{int(w)}" for w in _ETA_WAVELENGTHS]
    return table["theta_deg"], np.log(np.stack([table[c] for c in columns], axis=-1))


def _wavelength_weights(wl: NDArray[np.float64], nodes: NDArray[np.float64]) -> NDArray[np.float64]:
    """(len(nodes), n) matrix W with f(wl) = f(nodes) @ W for piecewise-linear f held beyond the ends."""
    eye = np.eye(nodes.size)
    return np.stack([np.interp(wl, nodes, eye[k]) for k in range(nodes.size)], axis=0)


def mie_eta(theta: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
    """Scattering term eta(theta, lambda) of Preetham (1999) Table 1 (v = 4) [-], shape (..., n).

    Parameters
    ----------
    theta : array_like, shape (...)
        Scattering angle [rad], in [0, pi].
    wavelengths : array_like, shape (n,)
        Wavelengths [nm].
    """
    th_deg = np.degrees(scattering_angles(theta))
    wl, _ = wavelengths_m(wavelengths)
    nodes, log_eta = _eta_log_table()
    flat = th_deg.reshape(-1)
    # log-linear in theta per table column, then linear in wavelength
    per_column = np.stack([np.interp(flat, nodes, log_eta[:, k]) for k in range(log_eta.shape[1])], axis=-1)
    eta = np.exp(per_column) @ _wavelength_weights(wl, _ETA_WAVELENGTHS)
    return eta.reshape(th_deg.shape + (wl.size,))


def _prefactor(wavelengths: ArrayLike, turbidity: float) -> NDArray[np.float64]:
    """0.434 c_SI (2 pi / lambda)^(v - 2) [m^-1], shape (n,)."""
    _, lam = wavelengths_m(wavelengths)
    c_si = haze_concentration(turbidity) * _C_TO_SI
    return 0.434 * c_si * (2.0 * np.pi / lam) ** (JUNGE_EXPONENT - 2.0)


def mie_total_scattering(wavelengths: ArrayLike, turbidity: float) -> NDArray[np.float64]:
    """Total Mie (haze) scattering coefficient beta_p [m^-1] at sea level (Preetham 1999, A.3, Table 2).

    ``0.434 c pi (2 pi / lambda)^(v - 2) K`` with c converted from cgs to SI (module docstring).

    Parameters
    ----------
    wavelengths : array_like, shape (n,)
        Wavelengths [nm].
    turbidity : float
        Turbidity T >= 1 [-].

    Returns
    -------
    ndarray, shape (n,)
        beta_p [m^-1]; about 7.9e-5 m^-1 at 550 nm for T = 2.
    """
    return np.pi * _prefactor(wavelengths, turbidity) * mie_k(wavelengths)


def mie_angular_scattering(theta: ArrayLike, wavelengths: ArrayLike, turbidity: float) -> NDArray[np.float64]:
    """Angular Mie scattering coefficient beta_p(theta) [m^-1 sr^-1] (Preetham 1999, A.3, Table 1).

    ``0.434 c (2 pi / lambda)^(v - 2) eta(theta, lambda) / 2`` with c converted from cgs to SI. Its integral
    over the sphere is :func:`eta_integral_ratio` times :func:`mie_total_scattering` (1.005, the published
    tables' own small inconsistency); it is not renormalised.

    Parameters
    ----------
    theta : array_like, shape (...)
        Scattering angle [rad], in [0, pi].
    wavelengths : array_like, shape (n,)
        Wavelengths [nm].
    turbidity : float
        Turbidity T >= 1 [-].

    Returns
    -------
    ndarray, shape (..., n)
    """
    return 0.5 * _prefactor(wavelengths, turbidity) * mie_eta(theta, wavelengths)


def _eta_sphere_integral(wavelengths: ArrayLike) -> NDArray[np.float64]:
    """integral_0^pi eta(theta, lambda) sin(theta) dtheta [-], shape (n,) (fine trapezoidal quadrature)."""
    theta = np.linspace(0.0, np.pi, 3601)
    integrand = mie_eta(theta, wavelengths) * np.sin(theta)[:, None]
    return np.trapezoid(integrand, theta, axis=0)


def eta_integral_ratio(wavelengths: ArrayLike) -> NDArray[np.float64]:
    """Ratio (sphere integral of beta_p(theta)) / beta_p = integral eta sin dtheta / K [-], shape (n,).

    A measure of the consistency of Tables 1 and 2 (1 would be exact).
    """
    return _eta_sphere_integral(wavelengths) / mie_k(wavelengths)


def mie_phase_function(theta: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
    """Haze phase function [sr^-1] from Table 1, normalised to 1 over the sphere, shape (..., n).

    ``eta(theta, lambda) / (2 pi integral_0^pi eta sin dtheta)``.

    Parameters
    ----------
    theta : array_like, shape (...)
        Scattering angle [rad], in [0, pi].
    wavelengths : array_like, shape (n,)
        Wavelengths [nm].
    """
    return mie_eta(theta, wavelengths) / (2.0 * np.pi * _eta_sphere_integral(wavelengths))
