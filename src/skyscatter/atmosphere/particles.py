"""Particle components of the medium: one description for aerosols and cloud droplets in every solver.

A :class:`ParticleComponent` is one population of particles: a relative density profile
(:class:`~skyscatter.atmosphere.profiles.DensityProfile`, 1 = the density at which its coefficients are given),
and, at any wavelengths [nm], its extinction coefficient [m^-1] and single-scattering albedo [-] at relative
density 1 and its phase function as a :class:`~skyscatter.atmosphere.phase_table.PhaseTable`. The radiative
transfer equation needs exactly these per component: the scattering coefficient ``rho(h) beta_e omega``, the
absorption coefficient ``rho(h) beta_e (1 - omega)`` and the phase function ([Bruneton2008] Sec. 2.1;
[Chandrasekhar1960] Ch. I).

Kinds of component (each registered by its ``kind`` for :func:`particle_component_from_dict`):

* :class:`AnalyticParticles` (``"analytic"``) - a phase function in closed form (Cornette-Shanks or Henyey-
  Greenstein with one asymmetry ``g``) and a wavelength-independent albedo: the description of the default
  aerosol (:attr:`AtmosphereParameters.aerosol_component` builds it from the ``mie_*`` fields), which solvers
  evaluate with the formula (``analytic_phase``), so that the default sky stays bit for bit what it was;
* :class:`TabulatedParticles` (``"tabulated"``) - spectra and a phase table given as data (for example from Mie
  theory), used at wavelengths inside their range.

A solver reads the medium's components from :attr:`AtmosphereParameters.particle_components` (the aerosol
first, then any further components such as cloud layers); :meth:`AtmosphereParameters.aerosol_phase_table`
gives the aerosol's phase table at the solver's wavelengths. New kinds (Mie size distributions, cloud layers)
derive from :class:`ParticleComponent` and call :func:`register_particle_kind`.
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import FileFormatError, InvalidParameterError
from .phase_table import PhaseTable
from .profiles import DensityProfile
from .spectra import PowerLawSpectrum, Spectrum

__all__ = [
    "AnalyticParticles",
    "AnalyticPhase",
    "ParticleComponent",
    "TabulatedParticles",
    "particle_component_from_dict",
    "register_particle_kind",
]


class AnalyticPhase(NamedTuple):
    """An analytic phase function: ``kind`` from :data:`.phase.AEROSOL_PHASE_FUNCTIONS` and asymmetry ``g`` [-]."""

    kind: str
    g: float


def _wavelengths(wavelengths: ArrayLike) -> NDArray[np.float64]:
    from ..spectral import as_wavelengths

    return as_wavelengths(wavelengths)


class ParticleComponent(abc.ABC):
    """One population of particles in the medium (module docstring).

    Subclasses are frozen dataclasses with a ``name`` and a ``density`` (:class:`DensityProfile`), set the class
    attribute ``kind`` and implement :meth:`extinction_at`, :meth:`single_scattering_albedo_at`,
    :meth:`phase_table`, :meth:`to_dict` and ``from_dict``.
    """

    kind: ClassVar[str]
    name: str
    density: DensityProfile

    @abc.abstractmethod
    def extinction_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Extinction coefficient at relative density 1 [m^-1], shape (n_wl,)."""

    @abc.abstractmethod
    def single_scattering_albedo_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Single-scattering albedo (scattering / extinction) in [0, 1] [-], shape (n_wl,)."""

    @abc.abstractmethod
    def phase_table(self, wavelengths: ArrayLike, angles: ArrayLike | None = None) -> PhaseTable:
        """The phase function at ``wavelengths`` [nm] as a normalised table (``angles`` [rad], default the
        component's own grid or :func:`.phase_table.phase_angle_grid`)."""

    @abc.abstractmethod
    def to_dict(self) -> dict[str, Any]:
        """JSON-compatible description with a ``"kind"`` key (:func:`particle_component_from_dict` reads it)."""

    @property
    def analytic_phase(self) -> AnalyticPhase | None:
        """The phase function in closed form, when it has one (solvers may then use the formula); else None."""
        return None

    def scattering_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Scattering coefficient at relative density 1 [m^-1], shape (n_wl,)."""
        return self.extinction_at(wavelengths) * self.single_scattering_albedo_at(wavelengths)

    def absorption_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        """Absorption coefficient at relative density 1 [m^-1], shape (n_wl,)."""
        return self.extinction_at(wavelengths) - self.scattering_at(wavelengths)

    def optical_depth(self, wavelengths: ArrayLike, height: float) -> NDArray[np.float64]:
        """Vertical optical depth [-] from the ground to ``height`` [m], shape (n_wl,)."""
        return self.extinction_at(wavelengths) * self.density.column(float(height))


_KINDS: dict[str, type[ParticleComponent]] = {}


def register_particle_kind(cls: type[ParticleComponent]) -> type[ParticleComponent]:
    """Register a :class:`ParticleComponent` subclass under its ``kind`` (usable as a class decorator)."""
    kind = getattr(cls, "kind", None)
    if not isinstance(kind, str) or not kind:
        raise InvalidParameterError("a particle component class needs a non-empty string 'kind'")
    _KINDS[kind] = cls
    return cls


def particle_component_from_dict(data: dict[str, Any]) -> ParticleComponent:
    """Rebuild a component from its :meth:`~ParticleComponent.to_dict` (FileFormatError if malformed)."""
    if not isinstance(data, dict) or data.get("kind") not in _KINDS:
        if isinstance(data, dict) and data.get("kind") in _LAZY_KINDS:
            import importlib

            importlib.import_module(_LAZY_KINDS[data["kind"]])
        if not isinstance(data, dict) or data.get("kind") not in _KINDS:
            kind = data.get("kind") if isinstance(data, dict) else None
            raise FileFormatError(
                f"unknown particle component kind {kind!r}; known: {', '.join(sorted({*_KINDS, *_LAZY_KINDS}))}")
    try:
        return _KINDS[data["kind"]].from_dict(data)  # type: ignore[attr-defined]
    except (KeyError, TypeError, ValueError) as exc:
        if isinstance(exc, InvalidParameterError):
            raise
        raise FileFormatError(f"particle component {data.get('name', '?')!r} is malformed: {exc}") from None


#: Kinds defined in modules that are imported only when a description names them (module path by kind).
_LAZY_KINDS: dict[str, str] = {"opac": "skyscatter.atmosphere.aerosol_types",
                               "cloud_layer": "skyscatter.atmosphere.clouds"}


def _check_density(name: str, density: Any) -> None:
    if not isinstance(density, DensityProfile):
        raise InvalidParameterError(f"particle component {name!r}: density must be a DensityProfile")


@register_particle_kind
@dataclass(frozen=True)
class AnalyticParticles(ParticleComponent):
    """Particles with an analytic phase function and a constant single-scattering albedo.

    Parameters
    ----------
    name : str
        Label (e.g. ``"aerosol"``).
    density : DensityProfile
        Relative density.
    extinction : Spectrum or float
        Extinction coefficient at relative density 1 [m^-1] (a number is constant in wavelength).
    single_scattering_albedo : float
        In [0, 1] [-].
    phase_function : str
        ``"cornette-shanks"`` or ``"henyey-greenstein"`` (:mod:`.phase`).
    g : float
        Asymmetry parameter of the phase function, in (-1, 1) [-].
    """

    kind: ClassVar[str] = "analytic"
    name: str
    density: DensityProfile
    extinction: Spectrum
    single_scattering_albedo: float = 0.9
    phase_function: str = "cornette-shanks"
    g: float = 0.8

    def __post_init__(self) -> None:
        from . import phase

        _check_density(self.name, self.density)
        if not isinstance(self.extinction, Spectrum):
            try:
                ext = float(self.extinction)
            except (TypeError, ValueError):
                raise InvalidParameterError(
                    f"particle component {self.name!r}: extinction must be a Spectrum or a number [m^-1]") from None
            object.__setattr__(self, "extinction", PowerLawSpectrum(ext, 1000.0, 0.0, f"{self.name} extinction"))
        for label in ("single_scattering_albedo", "g"):
            v = getattr(self, label)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) or not math.isfinite(v):
                raise InvalidParameterError(f"particle component {self.name!r}: {label} must be a finite number")
            object.__setattr__(self, label, float(v))
        if not 0.0 <= self.single_scattering_albedo <= 1.0:
            raise InvalidParameterError(
                f"particle component {self.name!r}: single-scattering albedo must be in [0, 1]; "
                f"got {self.single_scattering_albedo:g}")
        if not -1.0 < self.g < 1.0:
            raise InvalidParameterError(f"particle component {self.name!r}: g must be in (-1, 1); got {self.g:g}")
        if not isinstance(self.phase_function, str):
            raise InvalidParameterError(f"particle component {self.name!r}: phase_function must be a name")
        phase.aerosol_phase_kind(self.phase_function)

    def extinction_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        return np.asarray(self.extinction(np.asarray(wavelengths, dtype=float)), dtype=float)

    def single_scattering_albedo_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        return np.full(np.shape(np.asarray(wavelengths, dtype=float)), self.single_scattering_albedo)

    def scattering_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        # the same product as AtmosphereParameters.mie_scattering_at (bit for bit)
        return self.extinction_at(wavelengths) * self.single_scattering_albedo

    @property
    def analytic_phase(self) -> AnalyticPhase:
        return AnalyticPhase(self.phase_function, self.g)

    def phase_table(self, wavelengths: ArrayLike, angles: ArrayLike | None = None) -> PhaseTable:
        return PhaseTable.from_analytic(self.phase_function, self.g, _wavelengths(wavelengths), angles)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "name": self.name, "density": self.density.to_dict(),
                "extinction": self.extinction.to_dict(), "single_scattering_albedo": self.single_scattering_albedo,
                "phase_function": self.phase_function, "g": self.g}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> AnalyticParticles:
        return cls(data["name"], DensityProfile.from_dict(data["density"]), Spectrum.from_dict(data["extinction"]),
                   float(data["single_scattering_albedo"]), data["phase_function"], float(data["g"]))


@register_particle_kind
@dataclass(frozen=True)
class TabulatedParticles(ParticleComponent):
    """Particles given as data: extinction and albedo spectra and a phase table (e.g. from Mie theory).

    Parameters
    ----------
    name : str
        Label.
    density : DensityProfile
        Relative density.
    extinction : Spectrum
        Extinction coefficient at relative density 1 [m^-1].
    single_scattering_albedo : Spectrum
        In [0, 1] [-].
    phase : PhaseTable
        Phase function at its wavelengths; used at wavelengths inside their range, linear in wavelength
        (:meth:`PhaseTable.at_wavelengths`).
    """

    kind: ClassVar[str] = "tabulated"
    name: str
    density: DensityProfile
    extinction: Spectrum
    single_scattering_albedo: Spectrum
    phase: PhaseTable

    def __post_init__(self) -> None:
        _check_density(self.name, self.density)
        for label in ("extinction", "single_scattering_albedo"):
            if not isinstance(getattr(self, label), Spectrum):
                raise InvalidParameterError(f"particle component {self.name!r}: {label} must be a Spectrum")
        if not isinstance(self.phase, PhaseTable):
            raise InvalidParameterError(f"particle component {self.name!r}: phase must be a PhaseTable")

    def extinction_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        return np.asarray(self.extinction(np.asarray(wavelengths, dtype=float)), dtype=float)

    def single_scattering_albedo_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        a = np.asarray(self.single_scattering_albedo(np.asarray(wavelengths, dtype=float)), dtype=float)
        if np.any((a < 0) | (a > 1)):
            raise InvalidParameterError(
                f"particle component {self.name!r}: single-scattering albedo must be in [0, 1]; got up to {a.max():g}")
        return a

    def phase_table(self, wavelengths: ArrayLike, angles: ArrayLike | None = None) -> PhaseTable:
        table = self.phase.at_wavelengths(_wavelengths(wavelengths))
        return table if angles is None else table.on_angles(angles)

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "name": self.name, "density": self.density.to_dict(),
                "extinction": self.extinction.to_dict(),
                "single_scattering_albedo": self.single_scattering_albedo.to_dict(), "phase": self.phase.to_dict()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TabulatedParticles:
        return cls(data["name"], DensityProfile.from_dict(data["density"]), Spectrum.from_dict(data["extinction"]),
                   Spectrum.from_dict(data["single_scattering_albedo"]), PhaseTable.from_dict(data["phase"]))
