"""Physical description of a planetary atmosphere for the precomputed model (Bruneton & Neyret 2008, Sec. 2.1).

:class:`AtmosphereParameters` holds everything the precomputation needs: planet and top-of-atmosphere radii,
density profiles, Rayleigh and Mie coefficients, Cornette-Shanks asymmetry, ozone absorption, ground albedo,
the top-of-atmosphere solar spectrum, the solar angular radius and the largest sun zenith angle to tabulate.
Defaults are the Earth values of the seeds README (after Bruneton's 2017 rewrite of the paper's model):

=====================  =========================================================================
planet / top radius    6360 km / 6420 km
Rayleigh               exponential, H_R = 8 km; beta_R = 1.24062e-6 m^-1 (lambda / 1 um)^-4,
                       i.e. (5.802, 13.558, 33.100)e-6 m^-1 at (680, 550, 440) nm (Eq. 1 shape)
Mie                    exponential, H_M = 1.2 km; Angstrom alpha = 0, beta = 5.328e-3, single-scattering
                       albedo 0.9: extinction 4.44e-6 m^-1, scattering 3.996e-6 m^-1; Cornette-Shanks g = 0.8
ozone                  tent 10-25-40 km, 300 DU, Serdyuchenko et al. (2014) 233 K cross-sections:
                       peak absorption (0.650, 1.881, 0.085)e-6 m^-1 at (680, 550, 440) nm
ground albedo          0.1
sun                    ASTM G173-03 extraterrestrial spectrum; angular radius 0.004675 rad
largest sun zenith     102 deg (twilight to the end of nautical dusk)
=====================  =========================================================================

Spectral quantities are :class:`Spectrum` objects (a power law or a tabulated function of wavelength), so
tables can be computed at any wavelengths.
"""

from __future__ import annotations

import abc
import dataclasses
import json
import math
from dataclasses import dataclass, field
from functools import cache, lru_cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FileFormatError, InvalidParameterError

__all__ = [
    "AtmosphereParameters",
    "DensityLayer",
    "DensityProfile",
    "DOBSON_UNIT",
    "PowerLawSpectrum",
    "Spectrum",
    "TabulatedSpectrum",
    "rayleigh_scattering_physical",
]

#: Molecules per square metre in one Dobson unit (0.01 mm of pure ozone at 273.15 K and 1 atm).
DOBSON_UNIT = 2.687e20
#: Width [nm] of the box filter applied to the solar spectrum before sampling it at a table wavelength.
SOLAR_BAND_WIDTH = 10.0


# --------------------------------------------------------------------------------------------- spectra


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

    ``beta(lambda) = 8 pi^3 (n^2 - 1)^2 / (3 N lambda^4) * (6 + 3 p) / (6 - 7 p)`` (Bruneton & Neyret 2008,
    Eq. 1, with the King correction factor for depolarisation ``p``; Bodhaine et al. 1999, J. Atmos. Oceanic
    Technol. 16, Eqs. 2 and 4). The refractive index of standard air (288.15 K, 1013.25 hPa, 300 ppm CO2) is
    Peck & Reeder (1972) as given by Bodhaine et al. Eq. 4; N = 2.546899e25 m^-3 is the molecular density at
    the same conditions. ``p = 0.035`` (Preetham et al. 1999) gives a King factor of 1.061.
    """

    depolarisation: float = 0.035
    name: str = "Rayleigh scattering (physics, King factor)"

    def __post_init__(self) -> None:
        if not 0.0 <= self.depolarisation < 6.0 / 7.0:
            raise InvalidParameterError(f"depolarisation factor must be in [0, 6/7); got {self.depolarisation!r}")

    @property
    def king_factor(self) -> float:
        """(6 + 3 p) / (6 - 7 p)."""
        p = self.depolarisation
        return (6.0 + 3.0 * p) / (6.0 - 7.0 * p)

    def __call__(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        wl_um = np.asarray(wavelengths, dtype=float) * 1e-3
        s2 = wl_um**-2
        n_minus_1 = 1e-8 * (8060.51 + 2480990.0 / (132.274 - s2) + 17455.7 / (39.32957 - s2))
        n = 1.0 + n_minus_1
        number_density = 2.546899e25
        wl_m = wl_um * 1e-6
        return 8.0 * np.pi**3 * (n * n - 1.0) ** 2 / (3.0 * number_density * wl_m**4) * self.king_factor

    def to_dict(self) -> dict[str, Any]:
        return {"kind": "rayleigh_physical", "depolarisation": self.depolarisation, "name": self.name}


def rayleigh_scattering_physical(depolarisation: float = 0.035) -> Spectrum:
    """Rayleigh scattering coefficient at sea level from the refractive index of air (see
    :class:`RayleighPhysicalSpectrum`); pass it as ``AtmosphereParameters(rayleigh_scattering=...)``."""
    return RayleighPhysicalSpectrum(float(depolarisation))


def _read_csv(name: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    text = resources.files("skyscatter.data").joinpath(name).read_text(encoding="utf-8")
    rows = [ln for ln in text.splitlines() if ln.strip() and not ln.startswith("#")]
    try:
        data = np.array([[float(x) for x in ln.split(",")] for ln in rows[1:]])
    except ValueError as exc:
        raise FileFormatError(f"skyscatter data file {name} is malformed: {exc}") from None
    return data[:, 0], data[:, 1]


@cache
def solar_spectrum_astm_g173() -> TabulatedSpectrum:
    """ASTM G173-03 extraterrestrial spectral irradiance [W m^-2 nm^-1], 280-1100 nm (data file)."""
    wl, v = _read_csv("solar_spectrum_astm_g173.csv")
    return TabulatedSpectrum(tuple(wl), tuple(v), "solar irradiance ASTM G173-03 ETR")


@cache
def ozone_cross_section_serdyuchenko() -> TabulatedSpectrum:
    """Ozone absorption cross-section [m^2] at 233 K, Serdyuchenko et al. (2014), 360-830 nm (data file)."""
    wl, v = _read_csv("ozone_serdyuchenko2014_233K.csv")
    return TabulatedSpectrum(tuple(wl), tuple(v), "ozone cross-section (Serdyuchenko et al. 2014, 233 K)")


# --------------------------------------------------------------------------------------------- profiles


@dataclass(frozen=True)
class DensityLayer:
    """One layer of a density profile: ``max(0, exp_term * exp(exp_scale * h) + linear_term * h + constant_term)``.

    ``h`` is the altitude above the planet surface [m]; ``width`` [m] is the thickness of the layer (ignored
    for the last layer of a profile, which extends upwards without limit).
    """

    width: float = 0.0
    exp_term: float = 0.0
    exp_scale: float = 0.0
    linear_term: float = 0.0
    constant_term: float = 0.0

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if not math.isfinite(v):
                raise InvalidParameterError(f"density layer {f.name} must be finite; got {v!r}")
        if self.width < 0:
            raise InvalidParameterError(f"density layer width must be >= 0 m; got {self.width!r}")


@dataclass(frozen=True)
class DensityProfile:
    """Relative density (1 = the reference density of the coefficients) as a stack of :class:`DensityLayer`."""

    layers: tuple[DensityLayer, ...]

    def __post_init__(self) -> None:
        if not self.layers:
            raise InvalidParameterError("a density profile needs at least one layer")
        object.__setattr__(self, "layers", tuple(self.layers))

    @classmethod
    def exponential(cls, scale_height: float) -> DensityProfile:
        """``exp(-h / scale_height)`` (Eqs. 1 and 3); ``scale_height`` [m] > 0."""
        if not (math.isfinite(scale_height) and scale_height > 0):
            raise InvalidParameterError(f"scale height must be > 0 m; got {scale_height!r}")
        return cls((DensityLayer(0.0, 1.0, -1.0 / scale_height, 0.0, 0.0),))

    @classmethod
    def tent(cls, bottom: float, peak: float, top: float) -> DensityProfile:
        """Piecewise-linear layer: 0 below ``bottom``, rising to 1 at ``peak``, 0 again from ``top`` [m]."""
        if not (0 <= bottom < peak < top and math.isfinite(top)):
            raise InvalidParameterError(f"tent profile needs 0 <= bottom < peak < top [m]; got {bottom}, {peak}, {top}")
        up = 1.0 / (peak - bottom)
        down = 1.0 / (top - peak)
        return cls((DensityLayer(peak, 0.0, 0.0, up, -bottom * up), DensityLayer(0.0, 0.0, 0.0, -down, top * down)))

    @classmethod
    def uniform(cls) -> DensityProfile:
        """Density 1 at every altitude."""
        return cls((DensityLayer(0.0, 0.0, 0.0, 0.0, 1.0),))

    def __call__(self, altitude: ArrayLike) -> NDArray[np.float64]:
        """Relative density at ``altitude`` [m] above the surface."""
        h = np.asarray(altitude, dtype=float)
        out = np.zeros_like(h)
        start = 0.0
        done = np.zeros(h.shape, dtype=bool)
        for k, layer in enumerate(self.layers):
            last = k == len(self.layers) - 1
            sel = ~done if last else (~done & (h < start + layer.width))
            v = layer.exp_term * np.exp(layer.exp_scale * h) + layer.linear_term * h + layer.constant_term
            out = np.where(sel, np.maximum(v, 0.0), out)
            done |= sel
            start += layer.width
        return out

    def column(self, height: float) -> float:
        """Integral of the relative density from the surface to ``height`` [m] (an equivalent thickness [m])."""
        return _profile_column(self, float(height))

    def as_array(self) -> NDArray[np.float64]:
        """Layers as an (n_layers, 5) array: width, exp_term, exp_scale, linear_term, constant_term."""
        return np.array([[la.width, la.exp_term, la.exp_scale, la.linear_term, la.constant_term] for la in self.layers])

    def to_dict(self) -> list[dict[str, float]]:
        return [dataclasses.asdict(la) for la in self.layers]

    @classmethod
    def from_dict(cls, data: list[dict[str, float]]) -> DensityProfile:
        return cls(tuple(DensityLayer(**la) for la in data))


@lru_cache(maxsize=64)
def _profile_column(profile: DensityProfile, height: float) -> float:
    # Fine trapezoid with the layer boundaries as nodes: exact for linear layers, better than 1e-6 relative
    # for exponential ones with scale heights of 1 km and more.
    edges = list(np.cumsum([0.0] + [lay.width for lay in profile.layers[:-1]]))
    # zero crossings of linear layers are kinks of max(0, .)
    edges += [-lay.constant_term / lay.linear_term for lay in profile.layers
              if lay.linear_term != 0 and lay.exp_term == 0]
    e = np.array(edges)
    nodes = np.unique(np.concatenate([np.linspace(0.0, height, 40001), e[(e > 0) & (e < height)]]))
    return float(np.trapezoid(profile(nodes), nodes))


def _as_spectrum(value: Any, name: str) -> Spectrum:
    if isinstance(value, Spectrum):
        return value
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be a number or a Spectrum; got {value!r}") from None
    return PowerLawSpectrum(v, 1000.0, 0.0, name)


# --------------------------------------------------------------------------------------------- parameters


@dataclass(frozen=True)
class AtmosphereParameters:
    """A spherical planet with a clear-sky atmosphere of molecules, aerosols and ozone.

    Parameters
    ----------
    bottom_radius, top_radius : float
        Planet radius and radius of the top of the atmosphere [m]; ``top_radius > bottom_radius``.
    rayleigh_density : DensityProfile
        Relative density of air molecules (default exponential with H_R = 8000 m).
    rayleigh_scattering : Spectrum or float
        Rayleigh scattering coefficient at relative density 1 [m^-1] (default ``1.24062e-6 (lambda/1 um)^-4``,
        Bruneton 2017; :func:`rayleigh_scattering_physical` gives the value from the refractive index).
        Molecules do not absorb: extinction equals scattering (Sec. 2.1).
    mie_density : DensityProfile
        Relative aerosol density (default exponential with H_M = 1200 m).
    mie_angstrom_alpha, mie_angstrom_beta : float
        Angstrom's law: the vertical aerosol optical depth is ``beta * (lambda / 1 um)^-alpha``; the
        extinction coefficient at relative density 1 [m^-1] is that divided by the column of ``mie_density``.
    mie_single_scattering_albedo : float
        beta_s / beta_e of aerosols, in [0, 1] (default 0.9).
    mie_phase_g : float
        Asymmetry parameter of the Cornette-Shanks phase function (Eq. 4), in (-1, 1) (default 0.8).
    ozone_density : DensityProfile
        Relative ozone density (default tent 10-25-40 km).
    ozone_column : float
        Total ozone [Dobson units] (default 300).
    ozone_cross_section : Spectrum
        Absorption cross-section [m^2] (default Serdyuchenko et al. 2014, 233 K).
    ground_albedo : Spectrum or float
        Lambertian reflectance of the ground, in [0, 1] (default 0.1).
    solar_irradiance : Spectrum
        Extraterrestrial spectral irradiance normal to the sun [W m^-2 nm^-1] (default ASTM G173-03). It is
        box-filtered over 10 nm before being sampled at a table wavelength.
    sun_angular_radius : float
        [rad] (default 0.004675).
    max_sun_zenith : float
        Largest sun zenith angle tabulated [rad], in [102 deg, 180 deg] (default 102 deg); the sky is dark
        beyond it.
    """

    bottom_radius: float = 6_360_000.0
    top_radius: float = 6_420_000.0
    rayleigh_density: DensityProfile = field(default_factory=lambda: DensityProfile.exponential(8000.0))
    rayleigh_scattering: Spectrum = field(
        default_factory=lambda: PowerLawSpectrum(1.24062e-6, 1000.0, -4.0, "Rayleigh scattering (Bruneton 2017)")
    )
    mie_density: DensityProfile = field(default_factory=lambda: DensityProfile.exponential(1200.0))
    mie_angstrom_alpha: float = 0.0
    mie_angstrom_beta: float = 5.328e-3
    mie_single_scattering_albedo: float = 0.9
    mie_phase_g: float = 0.8
    ozone_density: DensityProfile = field(default_factory=lambda: DensityProfile.tent(10_000.0, 25_000.0, 40_000.0))
    ozone_column: float = 300.0
    ozone_cross_section: Spectrum = field(default_factory=ozone_cross_section_serdyuchenko)
    ground_albedo: Spectrum = field(default_factory=lambda: PowerLawSpectrum(0.1, 1000.0, 0.0, "ground albedo"))
    solar_irradiance: Spectrum = field(default_factory=solar_spectrum_astm_g173)
    sun_angular_radius: float = 0.004675
    max_sun_zenith: float = math.radians(102.0)

    def __post_init__(self) -> None:
        for name in ("rayleigh_scattering", "ozone_cross_section", "ground_albedo", "solar_irradiance"):
            object.__setattr__(self, name, _as_spectrum(getattr(self, name), name.replace("_", " ")))
        scalars = ("bottom_radius", "top_radius", "mie_angstrom_alpha", "mie_angstrom_beta",
                   "mie_single_scattering_albedo", "mie_phase_g", "ozone_column", "sun_angular_radius",
                   "max_sun_zenith")
        for name in scalars:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v):
                raise InvalidParameterError(f"{name} must be a finite number; got {v!r}")
            object.__setattr__(self, name, float(v))
        if self.bottom_radius <= 0:
            raise InvalidParameterError(f"bottom_radius must be > 0 m; got {self.bottom_radius:g}")
        if self.top_radius <= self.bottom_radius:
            raise InvalidParameterError(
                f"top_radius ({self.top_radius:g} m) must be above bottom_radius ({self.bottom_radius:g} m)"
            )
        for name in ("rayleigh_density", "mie_density", "ozone_density"):
            if not isinstance(getattr(self, name), DensityProfile):
                raise InvalidParameterError(f"{name} must be a DensityProfile")
        if self.mie_angstrom_beta < 0:
            raise InvalidParameterError(f"mie_angstrom_beta must be >= 0; got {self.mie_angstrom_beta:g}")
        if not 0.0 <= self.mie_single_scattering_albedo <= 1.0:
            raise InvalidParameterError(
                f"mie_single_scattering_albedo must be in [0, 1]; got {self.mie_single_scattering_albedo:g}"
            )
        if not -1.0 < self.mie_phase_g < 1.0:
            raise InvalidParameterError(f"mie_phase_g must be in (-1, 1); got {self.mie_phase_g:g}")
        if self.ozone_column < 0:
            raise InvalidParameterError(f"ozone_column must be >= 0 DU; got {self.ozone_column:g}")
        if not 0.0 < self.sun_angular_radius < 0.1:
            raise InvalidParameterError(f"sun_angular_radius must be in (0, 0.1) rad; got {self.sun_angular_radius:g}")
        if not math.radians(102.0) - 1e-9 <= self.max_sun_zenith <= math.pi:
            raise InvalidParameterError(
                f"max_sun_zenith must be in [102, 180] deg (twilight needs at least 102 deg); got "
                f"{math.degrees(self.max_sun_zenith):.4g} deg"
            )
        if self.mie_angstrom_beta > 0 and self.mie_density.column(self.thickness) <= 0:
            raise InvalidParameterError("mie_density is zero everywhere but mie_angstrom_beta > 0")

    # ------------------------------------------------------------------ constructors

    @classmethod
    def from_turbidity(cls, turbidity: float, **changes: Any) -> AtmosphereParameters:
        """Earth defaults with aerosols from Linke-style turbidity T (Preetham et al. 1999, Appendix A.1).

        Angstrom ``alpha = 1.3`` and ``beta = 0.04608 T - 0.04586``, so the vertical aerosol optical depth is
        ``beta (lambda / 1 um)^-1.3``; spread over ``mie_density``. Valid for 1 <= T <= 20 (beta > 0).
        """
        t = float(turbidity)
        if not (math.isfinite(t) and 1.0 <= t <= 20.0):
            raise InvalidParameterError(f"turbidity must be in [1, 20]; got {turbidity!r}")
        return cls(mie_angstrom_alpha=1.3, mie_angstrom_beta=0.04608 * t - 0.04586, **changes)

    def replace(self, **changes: Any) -> AtmosphereParameters:
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    # ------------------------------------------------------------------ derived coefficients

    @property
    def mu_s_min(self) -> float:
        """Cosine of :attr:`max_sun_zenith`."""
        return math.cos(self.max_sun_zenith)

    @property
    def thickness(self) -> float:
        """top_radius - bottom_radius [m]."""
        return self.top_radius - self.bottom_radius

    def rayleigh_scattering_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Rayleigh scattering (= extinction) coefficient at relative density 1 [m^-1]."""
        return self.rayleigh_scattering(wavelengths)

    def mie_extinction_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Aerosol extinction coefficient at relative density 1 [m^-1] (Angstrom's law over the Mie column)."""
        wl = np.asarray(wavelengths, dtype=float)
        if self.mie_angstrom_beta == 0:
            return np.zeros_like(wl)
        column = self.mie_density.column(self.thickness)
        return self.mie_angstrom_beta * (wl / 1000.0) ** (-self.mie_angstrom_alpha) / column

    def mie_scattering_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Aerosol scattering coefficient at relative density 1 [m^-1]."""
        return self.mie_extinction_at(wavelengths) * self.mie_single_scattering_albedo

    def ozone_number_density_peak(self) -> float:
        """Ozone number density where the relative density is 1 [m^-3]."""
        if self.ozone_column == 0:
            return 0.0
        column = self.ozone_density.column(self.thickness)
        if column <= 0:
            raise InvalidParameterError("ozone_density is zero everywhere but ozone_column > 0")
        return self.ozone_column * DOBSON_UNIT / column

    def ozone_absorption_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Ozone absorption coefficient at relative density 1 [m^-1]."""
        wl = np.asarray(wavelengths, dtype=float)
        if self.ozone_column == 0:
            return np.zeros_like(wl)
        return self.ozone_cross_section(wl) * self.ozone_number_density_peak()

    def ground_albedo_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Ground albedo in [0, 1]."""
        a = np.asarray(self.ground_albedo(wavelengths), dtype=float)
        if np.any((a < 0) | (a > 1)):
            raise InvalidParameterError(f"ground albedo must be in [0, 1]; got values up to {np.max(a):g}")
        return a

    def solar_irradiance_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Top-of-atmosphere solar irradiance [W m^-2 nm^-1], averaged over 10 nm centred on each wavelength."""
        wl = np.asarray(wavelengths, dtype=float)
        offsets = np.linspace(-SOLAR_BAND_WIDTH / 2, SOLAR_BAND_WIDTH / 2, 41)
        spec = self.solar_irradiance
        if isinstance(spec, TabulatedSpectrum):
            lo, hi = spec.range
            if wl.size and (np.min(wl) - 5 < lo - 1e-9 or np.max(wl) + 5 > hi + 1e-9):
                raise InvalidParameterError(
                    f"{spec.name} covers {lo:g}-{hi:g} nm; table wavelengths must lie in "
                    f"{lo + 5:g}-{hi - 5:g} nm; got {np.min(wl):g}-{np.max(wl):g} nm"
                )
        samples = spec(wl[..., None] + offsets)
        return np.trapezoid(samples, offsets, axis=-1) / SOLAR_BAND_WIDTH

    def check_wavelengths(self, wavelengths: ArrayLike) -> None:
        """Raise InvalidParameterError if some spectral input is not defined at ``wavelengths`` [nm]."""
        self.rayleigh_scattering_at(wavelengths)
        self.ozone_absorption_at(wavelengths)
        self.ground_albedo_at(wavelengths)
        self.solar_irradiance_at(wavelengths)

    # ------------------------------------------------------------------ serialisation

    def to_dict(self) -> dict[str, Any]:
        """JSON-compatible description (used for the cache key and stored with saved tables)."""
        out: dict[str, Any] = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, Spectrum):
                out[f.name] = v.to_dict()
            elif isinstance(v, DensityProfile):
                out[f.name] = v.to_dict()
            else:
                out[f.name] = float(v)
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> AtmosphereParameters:
        """Inverse of :meth:`to_dict`."""
        kwargs: dict[str, Any] = {}
        try:
            for f in dataclasses.fields(cls):
                v = data[f.name]
                if f.name.endswith("_density"):
                    kwargs[f.name] = DensityProfile.from_dict(v)
                elif isinstance(v, dict):
                    kwargs[f.name] = Spectrum.from_dict(v)
                else:
                    kwargs[f.name] = float(v)
        except (KeyError, TypeError) as exc:
            raise FileFormatError(f"atmosphere parameters are incomplete or malformed: {exc}") from None
        return cls(**kwargs)

    def canonical_json(self) -> str:
        """Deterministic JSON text of :meth:`to_dict` (sorted keys, repr-exact floats)."""
        return json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
