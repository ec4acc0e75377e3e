"""Spectral inputs of the medium: functions of wavelength [nm] and the published data they come from.

* :class:`PowerLawSpectrum`, :class:`TabulatedSpectrum` - a power law (Angstrom's law, lambda^-4) or a table.
* :class:`RayleighPhysicalSpectrum` - Rayleigh scattering of standard air from the refractive index
  (:func:`skyscatter.atmosphere.rayleigh.rayleigh_scattering_bodhaine1999`; [Bodhaine1999]).
* :func:`solar_spectrum_astm_g173` - ASTM G173-03 extraterrestrial spectral irradiance ([ASTMG173]; data file
  ``solar_spectrum_astm_g173``).
* :func:`ozone_cross_section_serdyuchenko` - ozone absorption cross-sections at 233 K of [Serdyuchenko2014]
  (data file ``ozone_serdyuchenko2014_233K``).

The data files are read by :func:`skyscatter.atmosphere.tables.load_table`, the one loader of the package.
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FileFormatError, InvalidParameterError
from .rayleigh import DEPOLARISATION, king_factor, rayleigh_scattering_bodhaine1999
from .tables import tabulated

__all__ = [
    "DOBSON_UNIT",
    "AngstromSpectrum",
    "PowerLawSpectrum",
    "RayleighPhysicalSpectrum",
    "Spectrum",
    "TabulatedSpectrum",
    "ozone_cross_section_serdyuchenko",
    "rayleigh_scattering_physical",
    "solar_spectrum_astm_g173",
]

#: Molecules per square metre in one Dobson unit (0.01 mm of pure ozone at 273.15 K and 1 atm) [m^-2].
DOBSON_UNIT = 2.687e20


class Spectrum(abc.ABC):
    """A non-negative function of wavelength [nm]; call it with an array of wavelengths."""

    name: str

    @abc.abstractmethod
    def __call__(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Values at ``wavelengths`` [nm]."""

    @abc.abstractmethod
    def to_dict(self) -> dict[str, Any]:
        """A JSON-serialisable description that :meth:`from_dict` reads back."""

    @staticmethod
    def from_dict(data: dict[str, Any]) -> Spectrum:
        kind = data.get("kind")
        if kind == "power_law":
            return PowerLawSpectrum(data["coefficient"], data["reference_wavelength"], data["exponent"], data["name"])
        if kind == "table":
            return TabulatedSpectrum(tuple(data["wavelengths"]), tuple(data["values"]), data["name"])
        if kind == "rayleigh_physical":
            return RayleighPhysicalSpectrum(data["depolarisation"], data["name"])
        if kind == "angstrom":
            return AngstromSpectrum(data["beta"], data["alpha"], data["column"], data["name"])
        raise FileFormatError(f"unknown spectrum kind {kind!r} in atmosphere parameters")


@dataclass(frozen=True)
class PowerLawSpectrum(Spectrum):
    """``coefficient * (wavelength / reference_wavelength) ** exponent``; a constant when ``exponent`` is 0.

    Parameters
    ----------
    coefficient : float
        Value at the reference wavelength (units of the quantity).
    reference_wavelength : float
        [nm].
    exponent : float
        Power of the wavelength ratio (-4 for Rayleigh scattering, -alpha for Angstrom's law).
    """

    coefficient: float
    reference_wavelength: float = 1000.0
    exponent: float = 0.0
    name: str = "power law"

    def __post_init__(self) -> None:
        for label, v in (("coefficient", self.coefficient), ("exponent", self.exponent)):
            if not math.isfinite(v):
                raise InvalidParameterError(f"{self.name}: {label} must be finite; got {v!r}")
        if self.coefficient < 0:
            raise InvalidParameterError(f"{self.name}: must be >= 0; got {self.coefficient!r}")
        if not (math.isfinite(self.reference_wavelength) and self.reference_wavelength > 0):
            raise InvalidParameterError(f"{self.name}: reference wavelength must be > 0 nm")

    def __call__(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        wl = np.asarray(wavelengths, dtype=float)
        return self.coefficient * (wl / self.reference_wavelength) ** self.exponent

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "power_law", "coefficient": self.coefficient,
                "reference_wavelength": self.reference_wavelength, "exponent": self.exponent, "name": self.name}


@dataclass(frozen=True)
class AngstromSpectrum(Spectrum):
    """Extinction [m^-1] from Angstrom's law spread over a column: ``beta (lambda / 1 um)^-alpha / column``.

    [Angstrom1929]: the vertical optical depth is
    ``beta (lambda / 1 um)^-alpha``; divided by ``column`` [m], the integral of the component's relative density,
    it is the coefficient at relative density 1. ``beta`` >= 0 [-], ``alpha`` [-] finite, ``column`` > 0 [m].
    """

    beta: float
    alpha: float
    column: float
    name: str = "Angstrom extinction"

    def __post_init__(self) -> None:
        for label, v in (("beta", self.beta), ("alpha", self.alpha), ("column", self.column)):
            if not math.isfinite(v):
                raise InvalidParameterError(f"{self.name}: {label} must be finite; got {v!r}")
        if self.beta < 0:
            raise InvalidParameterError(f"{self.name}: beta must be >= 0; got {self.beta!r}")
        if self.column <= 0:
            raise InvalidParameterError(f"{self.name}: the density column must be > 0 m; got {self.column!r}")

    def __call__(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        wl = np.asarray(wavelengths, dtype=float)
        if self.beta == 0:
            return np.zeros_like(wl)
        return self.beta * (wl / 1000.0) ** (-self.alpha) / self.column

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "angstrom", "beta": self.beta, "alpha": self.alpha, "column": self.column, "name": self.name}


@dataclass(frozen=True)
class TabulatedSpectrum(Spectrum):
    """Linear interpolation in a table; wavelengths outside the table are refused.

    Parameters
    ----------
    wavelengths : tuple of float
        Strictly increasing wavelengths [nm].
    values : tuple of float
        Non-negative values (units of the quantity).
    """

    wavelengths: tuple[float, ...]
    values: tuple[float, ...]
    name: str = "table"

    def __post_init__(self) -> None:
        wl = np.asarray(self.wavelengths, dtype=float)
        v = np.asarray(self.values, dtype=float)
        if wl.ndim != 1 or wl.shape != v.shape or wl.size < 1:
            raise InvalidParameterError(f"{self.name}: wavelengths and values must be 1-D and of equal length")
        if not (np.all(np.isfinite(wl)) and np.all(np.isfinite(v))):
            raise InvalidParameterError(f"{self.name}: table contains NaN or infinite values")
        if np.any(np.diff(wl) <= 0):
            raise InvalidParameterError(f"{self.name}: wavelengths must be strictly increasing")
        if np.any(v < 0):
            raise InvalidParameterError(f"{self.name}: values must be >= 0; the smallest is {v.min():g}")
        object.__setattr__(self, "wavelengths", tuple(float(x) for x in wl))
        object.__setattr__(self, "values", tuple(float(x) for x in v))

    @property
    def range(self) -> tuple[float, float]:
        """Smallest and largest tabulated wavelength [nm]."""
        return self.wavelengths[0], self.wavelengths[-1]

    def __call__(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        wl = np.asarray(wavelengths, dtype=float)
        lo, hi = self.range
        if wl.size and (np.min(wl) < lo - 1e-9 or np.max(wl) > hi + 1e-9):
            raise InvalidParameterError(
                f"{self.name} is tabulated for {lo:g}-{hi:g} nm; asked for {np.min(wl):g}-{np.max(wl):g} nm"
            )
        return np.interp(wl, self.wavelengths, self.values)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "table", "wavelengths": list(self.wavelengths), "values": list(self.values),
                "name": self.name}


@dataclass(frozen=True)
class RayleighPhysicalSpectrum(Spectrum):
    """Rayleigh scattering coefficient of standard air at sea level [m^-1] from the physics.

    :func:`skyscatter.atmosphere.rayleigh.rayleigh_scattering_bodhaine1999`: ``8 pi^3 (n^2 - 1)^2 / (3 N
    lambda^4) * (6 + 3 p) / (6 - 7 p)`` (Bruneton & Neyret 2008, Eq. 1, with the King factor; Bodhaine et al.
    1999, Eqs. 2-4) with Peck & Reeder's (1972) refractive index of standard air and N = 2.546899e25 m^-3.
    ``p = 0.035`` (Preetham et al. 1999) gives a King factor of 1.061.
    """

    depolarisation: float = DEPOLARISATION
    name: str = "Rayleigh scattering (physics, King factor)"

    def __post_init__(self) -> None:
        king_factor(self.depolarisation)  # validates

    @property
    def king_factor(self) -> float:
        """(6 + 3 p) / (6 - 7 p)."""
        return king_factor(self.depolarisation)

    def __call__(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        wl = np.asarray(wavelengths, dtype=float)
        flat = rayleigh_scattering_bodhaine1999(wl.reshape(-1), depolarisation=self.depolarisation)
        return flat.reshape(wl.shape)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "rayleigh_physical", "depolarisation": self.depolarisation, "name": self.name}


def rayleigh_scattering_physical(depolarisation: float = DEPOLARISATION) -> Spectrum:
    """Rayleigh scattering coefficient at sea level from the refractive index of air (see
    :class:`RayleighPhysicalSpectrum`); pass it as ``AtmosphereParameters(rayleigh_scattering=...)``."""
    return RayleighPhysicalSpectrum(float(depolarisation))


@cache
def solar_spectrum_astm_g173() -> TabulatedSpectrum:
    """ASTM G173-03 extraterrestrial spectral irradiance [W m^-2 nm^-1], 280-1100 nm (data file)."""
    wl, v = tabulated("solar_spectrum_astm_g173", "irradiance_W_m2_nm")
    return TabulatedSpectrum(tuple(wl), tuple(v), "solar irradiance ASTM G173-03 ETR")


@cache
def ozone_cross_section_serdyuchenko() -> TabulatedSpectrum:
    """Ozone absorption cross-section [m^2] at 233 K, Serdyuchenko et al. (2014), 360-830 nm (data file)."""
    wl, v = tabulated("ozone_serdyuchenko2014_233K", "cross_section_m2")
    return TabulatedSpectrum(tuple(wl), tuple(v), "ozone cross-section (Serdyuchenko et al. 2014, 233 K)")
