"""The medium: a spherical planet with a clear atmosphere of molecules, aerosols and ozone.

:class:`AtmosphereParameters` is the one description of the atmosphere for every model that integrates
through it: the precomputed tables of Bruneton & Neyret ([Bruneton2008] Sec. 2.1) and a path tracer. It holds
the planet and top-of-atmosphere radii, density profiles, Rayleigh and aerosol coefficients, the aerosol phase function,
ozone absorption, ground albedo, the top-of-atmosphere solar spectrum, the solar angular radius and the largest sun
zenith
angle to tabulate. Defaults are the Earth values of Bruneton's 2017 rewrite of the paper's model:

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

Medium queries for a path tracer, at altitudes h [m] above the ground and wavelengths [nm], each (..., n_wl)
[m^-1]: :meth:`~AtmosphereParameters.scattering_coefficients` (Rayleigh, aerosol),
:meth:`~AtmosphereParameters.absorption_coefficient` (aerosol absorption + ozone) and
:meth:`~AtmosphereParameters.extinction_coefficient` (their sum); phase functions
:meth:`~AtmosphereParameters.rayleigh_phase` / :meth:`~AtmosphereParameters.aerosol_phase` and their samplers
(:mod:`skyscatter.atmosphere.phase`). Above the top of the atmosphere every coefficient is 0.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FileFormatError, InvalidParameterError
from ..fileio import atomic_path
from . import phase as _phase
from .particles import AnalyticParticles, ParticleComponent, particle_component_from_dict
from .phase_table import PhaseTable
from .profiles import DensityLayer, DensityProfile
from .spectra import (
    DOBSON_UNIT,
    AngstromSpectrum,
    PowerLawSpectrum,
    Spectrum,
    TabulatedSpectrum,
    ozone_cross_section_serdyuchenko,
    solar_spectrum_astm_g173,
)

__all__ = [
    "AtmosphereParameters",
    "DensityLayer",
    "DensityProfile",
    "SOLAR_BAND_WIDTH",
]

#: Width [nm] of the box filter applied to the solar spectrum before sampling it at a table wavelength.
SOLAR_BAND_WIDTH = 10.0


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
        Asymmetry parameter g of the aerosol phase function, in (-1, 1) (default 0.8).
    mie_phase_function : str
        The aerosol phase function: ``"cornette-shanks"`` (default; Bruneton & Neyret 2008, Eq. 4) or
        ``"henyey-greenstein"`` (:mod:`skyscatter.atmosphere.phase`). The precomputed tables honour it.
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
    aerosol : ParticleComponent or None
        The aerosol as a particle component (:mod:`skyscatter.atmosphere.particles`: its own density profile,
        extinction and albedo spectra and phase table, e.g. a Mie aerosol type). None (default): the aerosol of
        the ``mie_*`` fields above (Angstrom's law, constant albedo, analytic phase), which
        :attr:`aerosol_component` describes as an :class:`~skyscatter.atmosphere.particles.AnalyticParticles`.
        When given, it replaces ``mie_density``, ``mie_angstrom_*``, ``mie_single_scattering_albedo`` and
        ``mie_phase_*`` (which are then ignored).
    particles : tuple of ParticleComponent
        Further particle components (cloud layers, more aerosol layers), each with its own profile and phase
        function (default none). Solvers that handle one aerosol only refuse them.
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
    mie_phase_function: str = "cornette-shanks"
    aerosol: ParticleComponent | None = None
    particles: tuple[ParticleComponent, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.mie_phase_function, str):
            raise InvalidParameterError(
                f"mie_phase_function must be one of {', '.join(_phase.AEROSOL_PHASE_FUNCTIONS)}; "
                f"got {self.mie_phase_function!r}"
            )
        _phase.aerosol_phase_kind(self.mie_phase_function)
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
        if self.aerosol is None and self.mie_angstrom_beta > 0 and self.mie_density.column(self.thickness) <= 0:
            raise InvalidParameterError("mie_density is zero everywhere but mie_angstrom_beta > 0")
        if self.aerosol is not None and not isinstance(self.aerosol, ParticleComponent):
            raise InvalidParameterError(
                f"aerosol must be a ParticleComponent (skyscatter.atmosphere.particles) or None; "
                f"got {type(self.aerosol).__name__}")
        if isinstance(self.particles, ParticleComponent):
            object.__setattr__(self, "particles", (self.particles,))
        try:
            object.__setattr__(self, "particles", tuple(self.particles))
        except TypeError:
            raise InvalidParameterError("particles must be a sequence of ParticleComponent") from None
        for comp in self.particles:
            if not isinstance(comp, ParticleComponent):
                raise InvalidParameterError(
                    f"particles must be ParticleComponent instances; got {type(comp).__name__}")

    # ------------------------------------------------------------------ constructors

    @classmethod
    def from_options(cls, base: AtmosphereParameters | None = None, **options: Any) -> AtmosphereParameters:
        """The atmosphere a user's options describe (``turbidity``, ``aerosol_optical_depth``, ``angstrom_alpha``,
        ``ground_albedo``, ``ozone_column``, ``mie_phase_g``, ``aerosol_type``, ``atmosphere_file``): ``base``
        (default: the Earth defaults) with each option given changed. The one way every caller builds an
        atmosphere from options: :func:`skyscatter.atmosphere.options.atmosphere_from_options`, whose list
        :data:`~skyscatter.atmosphere.options.ATMOSPHERE_OPTIONS` states each option's range once.
        """
        from .options import atmosphere_from_options  # deferred: options.py imports this module

        return atmosphere_from_options(base, **options)

    @classmethod
    def from_aerosol_optical_depth(cls, aerosol_optical_depth: float, angstrom_alpha: float = 1.3,
                                   **changes: Any) -> AtmosphereParameters:
        """Earth defaults with a vertical aerosol optical depth ``tau`` at 550 nm and Angstrom exponent ``alpha``.

        Angstrom's law ``tau(lambda) = beta (lambda / 1 um)^-alpha`` ([Angstrom1929])
        gives ``beta = tau (0.55)^alpha``; ``tau`` in [0, 10], ``alpha`` in [-1, 4] (default 1.3, Preetham 1999 A.1).
        """
        return cls.from_options(cls(**changes), aerosol_optical_depth=aerosol_optical_depth,
                                angstrom_alpha=angstrom_alpha)

    @classmethod
    def with_aerosol_type(cls, name: str, aerosol_optical_depth: float | None = None,
                          relative_humidity: float = 50.0, **changes: Any) -> AtmosphereParameters:
        """Earth defaults with an OPAC aerosol type as the aerosol (Hess et al. 1998;
        :mod:`skyscatter.atmosphere.aerosol_types`): Mie optics of its components, its vertical profile.

        ``name`` one of :data:`~skyscatter.atmosphere.aerosol_types.AEROSOL_TYPES` (``"continental-average"``,
        ``"maritime-clean"``, ``"urban"``, ``"desert"``, ...); ``aerosol_optical_depth`` the vertical optical
        depth at 550 nm in [0, 10] (None: the type's own number densities); ``relative_humidity`` [%] in
        [0, 99]. Other fields as keyword arguments.
        """
        from .aerosol_types import OpacAerosol

        top = float(changes.get("top_radius", cls.top_radius)) - float(changes.get("bottom_radius", cls.bottom_radius))
        return cls(aerosol=OpacAerosol.preset(name, aerosol_optical_depth, relative_humidity, top), **changes)

    @classmethod
    def from_turbidity(cls, turbidity: float, **changes: Any) -> AtmosphereParameters:
        """Earth defaults with aerosols from Linke-style turbidity T (Preetham et al. 1999, Appendix A.1).

        Angstrom ``alpha = 1.3`` and ``beta = 0.04608 T - 0.04586``
        (:func:`skyscatter.atmosphere.turbidity.angstrom_beta`), so the vertical aerosol optical depth is
        ``beta (lambda / 1 um)^-1.3``; spread over ``mie_density``. Valid for 1 <= T <= 20 (beta > 0).
        """
        return cls.from_options(cls(**changes), turbidity=turbidity)

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

    @property
    def aerosol_component(self) -> ParticleComponent:
        """The aerosol as a particle component: :attr:`aerosol` when set, else the ``mie_*`` fields as an
        :class:`~skyscatter.atmosphere.particles.AnalyticParticles` (``mie_density``; Angstrom extinction
        ``beta (lambda / 1 um)^-alpha / column``; ``mie_single_scattering_albedo``; ``mie_phase_function`` with
        ``mie_phase_g``), which gives the same coefficients bit for bit."""
        if self.aerosol is not None:
            return self.aerosol
        return _legacy_aerosol(self.mie_density, self.mie_angstrom_beta, self.mie_angstrom_alpha,
                               self.mie_single_scattering_albedo, self.mie_phase_function, self.mie_phase_g,
                               self.thickness)

    @property
    def particle_components(self) -> tuple[ParticleComponent, ...]:
        """Every particle component of the medium: :attr:`aerosol_component` first, then :attr:`particles`."""
        return (self.aerosol_component, *self.particles)

    def aerosol_phase_table(self, wavelengths: ArrayLike, angles: ArrayLike | None = None) -> PhaseTable:
        """The aerosol's phase function at ``wavelengths`` [nm] as a normalised table
        (:class:`~skyscatter.atmosphere.phase_table.PhaseTable`; ``angles`` [rad] default the component's grid).
        For the default analytic aerosol it tabulates the formula; solvers that have the formula can use it
        instead (``aerosol_component.analytic_phase``)."""
        return self.aerosol_component.phase_table(self._wavelengths(wavelengths), angles)

    def mie_extinction_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Aerosol extinction coefficient at relative density 1 [m^-1] (:attr:`aerosol_component`; by default
        Angstrom's law over the column of ``mie_density``)."""
        if self.aerosol is not None:
            return self.aerosol.extinction_at(wavelengths)
        wl = np.asarray(wavelengths, dtype=float)
        if self.mie_angstrom_beta == 0:
            return np.zeros_like(wl)
        return _angstrom_extinction(self.mie_density, self.mie_angstrom_beta, self.mie_angstrom_alpha,
                                    self.thickness)(wl)

    def mie_scattering_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Aerosol scattering coefficient at relative density 1 [m^-1]."""
        if self.aerosol is not None:
            return self.aerosol.scattering_at(wavelengths)
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

    # ------------------------------------------------------------------ the medium at an altitude (path tracer)

    def _altitude(self, altitude: ArrayLike) -> NDArray[np.float64]:
        h = np.asarray(altitude, dtype=float)
        if np.any(~np.isfinite(h)) or np.any(h < 0.0):
            raise InvalidParameterError(
                "altitude must be finite and >= 0 m above the ground (the planet's surface is bottom_radius)"
            )
        return h

    def _wavelengths(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        from ..spectral import as_wavelengths

        return as_wavelengths(wavelengths)

    def scattering_coefficients(
        self, altitude: ArrayLike, wavelengths: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Rayleigh and aerosol scattering coefficients [m^-1] at ``altitude``.

        Parameters
        ----------
        altitude : array_like, shape (...)
            Altitude above the ground [m], >= 0; 0 above the top of the atmosphere.
        wavelengths : array_like, shape (n_wl,)
            Wavelengths [nm].

        Returns
        -------
        rayleigh, particles : ndarray, shape (..., n_wl)
            ``rayleigh_density(h) beta_R(lambda)`` and the sum over :attr:`particle_components` of
            ``density(h) beta_s(lambda)`` (by default the aerosol's ``mie_density(h) beta_M,s(lambda)``) [m^-1].
        """
        h = self._altitude(altitude)
        wl = self._wavelengths(wavelengths)
        inside = (h <= self.thickness)[..., None]
        ray = np.where(inside, self.rayleigh_density(h)[..., None] * self.rayleigh_scattering_at(wl), 0.0)
        mie = np.where(inside, self._aerosol_density(h)[..., None] * self.mie_scattering_at(wl), 0.0)
        for comp in self.particles:
            mie = mie + np.where(inside, comp.density(h)[..., None] * comp.scattering_at(wl), 0.0)
        return ray, mie

    def _aerosol_density(self, h: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.mie_density(h) if self.aerosol is None else self.aerosol.density(h)

    def absorption_coefficient(self, altitude: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Absorption coefficient [m^-1] at ``altitude``: aerosol absorption plus ozone, shape (..., n_wl).

        Aerosol absorption is ``mie_density(h) (1 - albedo) beta_M,e`` (and the same for each further particle
        component); ozone ``ozone_density(h) sigma N_O3`` (molecules do not absorb; Bruneton & Neyret 2008, Sec.
        2.1, with ozone as in Bruneton 2017). Parameters as in :meth:`scattering_coefficients`.
        """
        h = self._altitude(altitude)
        wl = self._wavelengths(wavelengths)
        inside = (h <= self.thickness)[..., None]
        mie_abs = self.mie_extinction_at(wl) - self.mie_scattering_at(wl)
        out = (self._aerosol_density(h)[..., None] * mie_abs
               + self.ozone_density(h)[..., None] * self.ozone_absorption_at(wl))
        for comp in self.particles:
            out = out + comp.density(h)[..., None] * comp.absorption_at(wl)
        return np.where(inside, out, 0.0)

    def extinction_coefficient(self, altitude: ArrayLike, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Extinction coefficient [m^-1] at ``altitude``: Rayleigh + aerosol scattering + absorption,
        shape (..., n_wl). Parameters as in :meth:`scattering_coefficients`."""
        ray, mie = self.scattering_coefficients(altitude, wavelengths)
        return ray + mie + self.absorption_coefficient(altitude, wavelengths)

    def rayleigh_phase(self, cos_theta: ArrayLike) -> NDArray[np.float64]:
        """Rayleigh phase function [sr^-1] at the cosine of the scattering angle (:mod:`.phase`)."""
        return _phase.rayleigh_phase(cos_theta)

    def aerosol_phase(self, cos_theta: ArrayLike, wavelengths: ArrayLike | None = None) -> NDArray[np.float64]:
        """Aerosol phase function [sr^-1] at ``cos_theta`` [-].

        Without ``wavelengths``: the analytic phase (by default :attr:`mie_phase_function` with
        :attr:`mie_phase_g`), shape of ``cos_theta``; InvalidParameterError for a tabulated aerosol. With
        ``wavelengths`` [nm]: :meth:`aerosol_phase_table` evaluated there, shape (..., n_wl).
        """
        if wavelengths is not None:
            return self.aerosol_phase_table(wavelengths).evaluate(cos_theta)
        analytic = self.aerosol_component.analytic_phase
        if analytic is None:
            raise InvalidParameterError("the aerosol's phase function depends on wavelength: pass wavelengths [nm]")
        return _phase.aerosol_phase(cos_theta, analytic.g, analytic.kind)

    def sample_rayleigh_phase(self, size: int | tuple[int, ...], rng: Any = None) -> NDArray[np.float64]:
        """Cosines of scattering angles [-] drawn from the Rayleigh phase function (exact inverse CDF)."""
        return _phase.sample_rayleigh(size, rng)

    def sample_aerosol_phase(self, size: int | tuple[int, ...], rng: Any = None,
                             wavelength: float | None = None) -> NDArray[np.float64]:
        """Cosines of scattering angles [-] drawn from the aerosol phase function: the analytic one
        (:func:`skyscatter.atmosphere.phase.sample_aerosol_phase`) without ``wavelength``, else the aerosol's
        phase table at ``wavelength`` [nm] (:meth:`~skyscatter.atmosphere.phase_table.PhaseTable.sample`)."""
        if wavelength is not None:
            return self.aerosol_phase_table([float(wavelength)]).sample(size, 0, rng)
        analytic = self.aerosol_component.analytic_phase
        if analytic is None:
            raise InvalidParameterError("the aerosol's phase function depends on wavelength: pass a wavelength [nm]")
        return _phase.sample_aerosol_phase(size, analytic.g, analytic.kind, rng)

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
            if f.name in ("aerosol", "particles"):
                # absent when unset, so that the descriptions (and cache keys) of the default air do not change
                if f.name == "aerosol" and v is not None:
                    out["aerosol"] = v.to_dict()
                elif f.name == "particles" and v:
                    out["particles"] = [c.to_dict() for c in v]
                continue
            if isinstance(v, Spectrum):
                out[f.name] = v.to_dict()
            elif isinstance(v, DensityProfile):
                out[f.name] = v.to_dict()
            elif isinstance(v, str):
                out[f.name] = v
            else:
                out[f.name] = float(v)
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> AtmosphereParameters:
        """Inverse of :meth:`to_dict`.

        A description written before ``mie_phase_function`` existed (older caches and table files) has no
        such key and gets the Cornette-Shanks phase function it was computed with; one without ``aerosol`` or
        ``particles`` has the default (the ``mie_*`` aerosol, no further components).
        """
        kwargs: dict[str, Any] = {}
        try:
            for f in dataclasses.fields(cls):
                if f.name == "mie_phase_function":
                    kwargs[f.name] = data.get(f.name, "cornette-shanks")
                    continue
                if f.name == "aerosol":
                    if data.get("aerosol") is not None:
                        kwargs["aerosol"] = particle_component_from_dict(data["aerosol"])
                    continue
                if f.name == "particles":
                    kwargs["particles"] = tuple(particle_component_from_dict(c) for c in data.get("particles", ()))
                    continue
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

    def save_json(self, path: str, extra: dict[str, Any] | None = None) -> None:
        """Write ``{"atmosphere": to_dict(), **extra}`` as JSON to ``path`` atomically (``skyscatter
        fit-atmosphere`` adds its fit report as ``extra``); :meth:`load_json` reads it back."""
        with atomic_path(path) as tmp:
            tmp.write_text(json.dumps({"atmosphere": self.to_dict(), **(extra or {})}, indent=1, sort_keys=True))

    @classmethod
    def load_json(cls, path: str) -> AtmosphereParameters:
        """The atmosphere of a JSON file: ``{"atmosphere": {...}}`` (:meth:`save_json`, ``skyscatter
        fit-atmosphere``) or a bare :meth:`to_dict` mapping. FileFormatError naming the file if it is unreadable."""
        from pathlib import Path

        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except OSError as exc:
            raise FileFormatError(f"cannot read the atmosphere file {path}: {exc.strerror or exc}") from None
        except ValueError as exc:
            raise FileFormatError(f"{path}: not a JSON file ({exc})") from None
        if isinstance(data, dict) and isinstance(data.get("atmosphere"), dict):
            data = data["atmosphere"]
        if not isinstance(data, dict):
            raise FileFormatError(f"{path}: expected an atmosphere description (a JSON object)")
        try:
            return cls.from_dict(data)
        except FileFormatError as exc:
            raise FileFormatError(f"{path}: {exc}") from None

    def canonical_json(self) -> str:
        """Deterministic JSON text of :meth:`to_dict` (sorted keys, repr-exact floats)."""
        return json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))


@lru_cache(maxsize=64)
def _angstrom_extinction(density: DensityProfile, beta: float, alpha: float, thickness: float) -> AngstromSpectrum:
    return AngstromSpectrum(beta, alpha, density.column(thickness), "aerosol extinction (Angstrom)")


@lru_cache(maxsize=64)
def _legacy_aerosol(density: DensityProfile, beta: float, alpha: float, albedo: float, kind: str, g: float,
                    thickness: float) -> AnalyticParticles:
    ext: Spectrum = (_angstrom_extinction(density, beta, alpha, thickness) if beta > 0
                     else PowerLawSpectrum(0.0, 1000.0, 0.0, "aerosol extinction"))
    return AnalyticParticles("aerosol", density, ext, albedo, kind, g)
