"""Broadband pieces of the clear atmosphere that the medium does not hold: water vapour and the uniformly mixed
gases, the solar spectrum above 1100 nm, and the medium's own slant optical masses.

The medium (:class:`~skyscatter.atmosphere.medium.AtmosphereParameters`) describes the scatterers (molecules,
aerosols, particle layers) and ozone over the wavelengths of its data (ozone cross-sections 360-830 nm, the
ASTM G173 sun 280-1100 nm). A weather file's direct normal and diffuse horizontal irradiance are broadband
(about 280-4000 nm): relating them to the medium needs the absorption of water vapour and of O2/CO2 in the near
infrared, and the sun's spectrum up to 4000 nm. Those come from here:

* :func:`water_vapour_transmittance`, :func:`mixed_gas_transmittance` and :func:`ozone_transmittance_bird_riordan`
  - Bird & Riordan (1986) [BirdRiordan1986], Eqs. 2-8, 2-9 and 2-11 with their Table 1 coefficients
  (data file ``bird_riordan1986_gas_absorption.csv``, 122 wavelengths 300-4000 nm, interpolated linearly between
  them). These are band transmittances (the water and O2 bands are not Beer-law at that resolution), so they
  multiply the medium's transmittance rather than entering the medium as absorption coefficients. The ozone
  form is used only outside the medium's ozone data (below 360 nm and above 830 nm);
* :func:`broadband_solar_spectrum` - ASTM G173-03 [ASTMG173] extraterrestrial spectrum 280-4000 nm (the medium's
  280-1100 nm table and ``solar_spectrum_astm_g173_nir.csv`` above it);
* :func:`slant_optical_masses` - the relative optical masses of the medium's own density profiles along a
  straight path through the spherical shell (no refraction, as in the precomputed tables), per component.
"""

from __future__ import annotations

from functools import cache
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from .spectra import solar_spectrum_astm_g173
from .tables import load_table

__all__ = [
    "OpticalMasses",
    "broadband_solar_spectrum",
    "gas_coefficients",
    "mixed_gas_transmittance",
    "ozone_transmittance_bird_riordan",
    "slant_optical_masses",
    "water_vapour_transmittance",
]

#: Pressure [Pa] of Bird & Riordan's pressure-corrected air mass (their 1013 mb).
REFERENCE_PRESSURE = 101_300.0


@cache
def gas_coefficients() -> dict[str, NDArray[np.float64]]:
    """Bird & Riordan (1986) Table 1: ``wavelength`` [nm], ``water_vapour`` a_w [cm^-1], ``ozone`` a_o [cm^-1],
    ``mixed_gas`` a_u [km^-1] at their 122 wavelengths (data file)."""
    t = load_table("bird_riordan1986_gas_absorption")
    return {"wavelength": t["wavelength_nm"], "water_vapour": t["water_vapour_cm-1"], "ozone": t["ozone_cm-1"],
            "mixed_gas": t["mixed_gas_km-1"]}


def _coefficient(name: str, wavelengths: ArrayLike) -> NDArray[np.float64]:
    c = gas_coefficients()
    wl = np.asarray(wavelengths, dtype=float)
    # below 300 nm (the first tabulated wavelength) there is no water or mixed-gas absorption in the table's sense
    return np.interp(wl, c["wavelength"], c[name], left=c[name][0], right=c[name][-1])


def _non_negative(name: str, value: ArrayLike) -> NDArray[np.float64]:
    v = np.asarray(value, dtype=float)
    if np.any(~np.isfinite(v)) or np.any(v < 0):
        raise InvalidParameterError(f"{name} must be finite and >= 0")
    return v


def water_vapour_transmittance(wavelengths: ArrayLike, precipitable_water: ArrayLike,
                               air_mass: ArrayLike) -> NDArray[np.float64]:
    """Water vapour band transmittance (Bird & Riordan 1986, Eq. 2-8)
    ``T_w = exp(-0.2385 a_w W M / (1 + 20.07 a_w W M)^0.45)``.

    Parameters
    ----------
    wavelengths : array_like, shape (n_wl,)
        [nm].
    precipitable_water : array_like, shape (...)
        Precipitable water W [cm] (>= 0).
    air_mass : array_like, shape (...)
        Relative optical air mass M [-] (>= 0) of the path.

    Returns
    -------
    ndarray, shape broadcast(W, M) + (n_wl,)
    """
    aw = _coefficient("water_vapour", wavelengths)
    wm = (_non_negative("precipitable water", precipitable_water)
          * _non_negative("air mass", air_mass))[..., None] * aw
    return np.exp(-0.2385 * wm / (1.0 + 20.07 * wm) ** 0.45)


def mixed_gas_transmittance(wavelengths: ArrayLike, air_mass: ArrayLike,
                            pressure: ArrayLike = REFERENCE_PRESSURE) -> NDArray[np.float64]:
    """Uniformly mixed gas (O2, CO2) transmittance (Bird & Riordan 1986, Eq. 2-11)
    ``T_u = exp(-1.41 a_u M' / (1 + 118.93 a_u M')^0.45)`` with ``M' = M p / 101300 Pa``.

    Parameters
    ----------
    wavelengths : array_like, shape (n_wl,)
        [nm].
    air_mass : array_like, shape (...)
        Relative optical air mass M [-].
    pressure : array_like, shape (...)
        Surface pressure p [Pa] (default 101300).

    Returns
    -------
    ndarray, shape broadcast(M, p) + (n_wl,)
    """
    au = _coefficient("mixed_gas", wavelengths)
    m = (_non_negative("air mass", air_mass) * _non_negative("pressure", pressure) / REFERENCE_PRESSURE)
    am = m[..., None] * au
    return np.exp(-1.41 * am / (1.0 + 118.93 * am) ** 0.45)


def ozone_transmittance_bird_riordan(wavelengths: ArrayLike, ozone_column: ArrayLike,
                                     ozone_mass: ArrayLike) -> NDArray[np.float64]:
    """Ozone transmittance ``exp(-a_o O3 M_o)`` (Bird & Riordan 1986, Eq. 2-9); ``ozone_column`` in Dobson units
    (1000 DU = 1 atm-cm), ``ozone_mass`` the ozone layer's relative optical mass [-]. Shape broadcast + (n_wl,).
    Only for wavelengths outside the medium's ozone table (below 360 nm, above 830 nm)."""
    ao = _coefficient("ozone", wavelengths)
    o3 = _non_negative("ozone column", ozone_column) / 1000.0 * _non_negative("ozone mass", ozone_mass)
    return np.exp(-o3[..., None] * ao)


@cache
def broadband_solar_spectrum() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """ASTM G173-03 extraterrestrial spectrum 280-4000 nm: ``(wavelengths [nm], irradiance [W m^-2 nm^-1])`` at
    the native sampling (0.5 nm below 400 nm, 1 nm to 1700 nm, 5 nm above) and the mean Sun-Earth distance.
    Integrates to 1366.1 W m^-2."""
    vis = solar_spectrum_astm_g173()
    nir = load_table("solar_spectrum_astm_g173_nir")
    wl = np.concatenate([np.asarray(vis.wavelengths), nir["wavelength_nm"]])
    e0 = np.concatenate([np.asarray(vis.values), nir["irradiance_W_m2_nm"]])
    wl.flags.writeable = False
    e0.flags.writeable = False
    return wl, e0


class OpticalMasses(NamedTuple):
    """Relative optical masses [-] (slant column over vertical column from the observer up) of the medium's
    components, each shape (n,)."""

    rayleigh: NDArray[np.float64]
    aerosol: NDArray[np.float64]
    ozone: NDArray[np.float64]


def slant_optical_masses(params, zenith: ArrayLike, observer_altitude: float = 0.0, *,
                         nodes: int = 801) -> OpticalMasses:
    """Relative optical masses of the medium's Rayleigh, aerosol and ozone profiles towards ``zenith``.

    ``m_c = int rho_c(h(s)) ds / int_{h0}^{top} rho_c(h) dh`` along the straight ray from the observer at
    ``observer_altitude`` [m] through the spherical shell to the top of the atmosphere (the geometry of the
    precomputed tables' transmittance, Bruneton & Neyret 2008, Eq. 5, without refraction). The path is
    sampled at ``nodes`` points spaced quadratically from the observer (fine where the density is high) and
    integrated by the trapezoid rule; the vertical column with the same rule. At the zenith ``m = 1``.

    Parameters
    ----------
    params : AtmosphereParameters
    zenith : array_like, shape (n,)
        Zenith angle of the path [rad], in [0, pi/2] (the path must not meet the ground).
    observer_altitude : float
        [m] above the ground, below the top of the atmosphere.

    Returns
    -------
    OpticalMasses
    """
    z = np.atleast_1d(np.asarray(zenith, dtype=float))
    if np.any(~np.isfinite(z)) or np.any(z < 0) or np.any(z > np.pi / 2 + 1e-12):
        raise InvalidParameterError("zenith angles for the optical masses must be in [0, pi/2] rad")
    h0 = float(observer_altitude)
    if not 0.0 <= h0 < params.thickness:
        raise InvalidParameterError(f"observer altitude must be in [0, {params.thickness:g}) m; got {h0:g}")
    r0 = params.bottom_radius + h0
    top = params.top_radius
    mu = np.cos(np.minimum(z, np.pi / 2))
    length = -r0 * mu + np.sqrt(np.maximum(r0 * r0 * (mu * mu - 1.0) + top * top, 0.0))
    t = np.linspace(0.0, 1.0, int(nodes)) ** 2
    s = length[:, None] * t
    h = np.sqrt(r0 * r0 + s * s + 2.0 * r0 * s * mu[:, None]) - params.bottom_radius
    h = np.clip(h, 0.0, params.thickness)
    hv = h0 + (params.thickness - h0) * t
    out = []
    for profile in (params.rayleigh_density, params.aerosol_component.density, params.ozone_density):
        slant = np.trapezoid(profile(h), s, axis=1)
        vertical = float(np.trapezoid(profile(hv), hv))
        out.append(slant / vertical if vertical > 0 else np.ones_like(slant))
    return OpticalMasses(*out)
