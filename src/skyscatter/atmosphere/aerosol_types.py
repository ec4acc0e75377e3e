"""Aerosol types of the OPAC climatology, with Mie optics: components, humidity growth and presets.

Source of every number: [Hess1998], the OPAC climatology.

**Components** (Table 1; data file ``opac_components.csv``): log-normal modes (number mode radius ``r_mod``, width
``sigma``, radius limits ``r_min``-``r_max``) with a refractive index per wavelength; the four hygroscopic
components (water-soluble, both sea-salt modes, sulfate) at the relative humidities 0, 50, 70, 80, 90, 95, 98
and 99 % with their wet mode radii, limits and indices (OPAC's humidity growth). Between two of those humidities
the radii and the index are interpolated linearly in humidity.

=========  ===========================  ============  ======  =========
code       component                    r_mod [um]    sigma   hygroscopic
=========  ===========================  ============  ======  =========
``inso``   insoluble                    0.471         2.51    no
``waso``   water-soluble                0.0212 (dry)  2.24    yes
``soot``   soot                         0.0118        2.00    no
``ssam``   sea salt, accumulation       0.209 (dry)   2.03    yes
``sscm``   sea salt, coarse             1.75 (dry)    2.03    yes
``minm``   mineral, nucleation          0.07          1.95    no
``miam``   mineral, accumulation        0.39          2.00    no
``micm``   mineral, coarse              1.90          2.15    no
``mitr``   mineral, transported         0.5           2.20    no
``suso``   sulfate droplets             0.0695 (dry)  2.03    yes
=========  ===========================  ============  ======  =========

**Types** (Table 4: number densities [cm^-3] of each component near the ground; scale height ``Z`` of the
exponential decrease in the mixing layer of height ``H``):

=======================  ===================================================  =======  =======
type                     components [cm^-3]                                   Z [km]   H [km]
=======================  ===================================================  =======  =======
continental-clean        waso 2600, inso 0.15                                 8        2
continental-average      waso 7000, inso 0.4, soot 8300                       8        2
continental-polluted     waso 15700, inso 0.6, soot 34300                     8        2
urban                    waso 28000, inso 1.5, soot 130000                    8        2
desert                   waso 2000, minm 269.5, miam 30.5, micm 0.142         2        6
maritime-clean           waso 1500, ssam 20, sscm 3.2e-3                      1        2
maritime-polluted        waso 3800, soot 5180, ssam 20, sscm 3.2e-3           1        2
maritime-tropical        waso 590, ssam 10, sscm 1.3e-3                       1        2
arctic                   waso 1300, inso 0.01, soot 5300, ssam 1.9            99       2
antarctic                suso 42.9, ssam 0.047, mitr 0.0053                   8        10
=======================  ===================================================  =======  =======

OPAC's free-tropospheric and stratospheric layers above the mixing layer are not included: a type here is its
mixing-layer aerosol, and :class:`OpacAerosol` usually rescales it to a given optical depth at 550 nm. Its vertical
profile is an exponential with the scale height ``H_c = Z (1 - exp(-H / Z))`` that holds the same column as OPAC's
``exp(-h / Z)`` cut at ``H`` (1.77 km for the continental types, 0.86 km maritime, 1.90 km desert): the precomputed
tables integrate exponential layers exactly (product integration along their rays), while the density jump at the
top of a mixing layer cost them 5 % in single scattering against an independent integral (measured for
continental-average, optical depth 0.2; docs/aerosols.md).

The optics of a mixture (Hess et al. 1998, Eqs. 1-2, external mixture): extinction ``sum_i N_i C_e,i``,
scattering ``sum_i N_i C_s,i`` and phase function ``sum_i N_i C_s,i p_i / sum_i N_i C_s,i``, each component's
``C`` and ``p`` from :func:`.mie_optics.mie_optics`, cached on disk per component, humidity and set of wavelengths
(:func:`.mie_optics.stored_mie_optics`), so that only the first process that needs them computes them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cache
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from .particles import ParticleComponent, register_particle_kind
from .phase_table import PhaseTable
from .profiles import DensityProfile
from .tables import load_table

__all__ = [
    "AEROSOL_TYPES",
    "OPAC_COMPONENTS",
    "AerosolType",
    "OpacAerosol",
    "opac_component",
]

#: OPAC component codes in the order of their ids in ``opac_components.csv``.
OPAC_COMPONENTS = ("inso", "waso", "soot", "ssam", "sscm", "minm", "miam", "micm", "mitr", "suso")
_COMPONENT_NAMES = {
    "inso": "insoluble", "waso": "water-soluble", "soot": "soot", "ssam": "sea salt (accumulation mode)",
    "sscm": "sea salt (coarse mode)", "minm": "mineral (nucleation mode)", "miam": "mineral (accumulation mode)",
    "micm": "mineral (coarse mode)", "mitr": "mineral (transported)", "suso": "sulfate droplets",
}


@dataclass(frozen=True)
class AerosolType:
    """An OPAC aerosol type (Hess et al. 1998, Table 4): number densities [cm^-3] per component, the scale
    height [m] of their decrease with altitude and the mixing-layer height [m]."""

    name: str
    components: tuple[tuple[str, float], ...]
    scale_height: float
    mixing_height: float

    @property
    def column_height(self) -> float:
        """Column [m] of OPAC's mixing-layer profile ``exp(-h / Z)`` for ``0 <= h <= H``: ``Z (1 - exp(-H / Z))``."""
        return self.scale_height * -math.expm1(-self.mixing_height / self.scale_height)

    def profile(self) -> DensityProfile:
        """``exp(-h / H_c)`` with ``H_c`` = :attr:`column_height`: the same number of particles per unit area as
        OPAC's mixing layer, without the density jump at its top (module docstring)."""
        return DensityProfile.exponential(self.column_height)


_KM = 1000.0
#: The aerosol types of Hess et al. (1998), Table 4 (module docstring), by name.
AEROSOL_TYPES: dict[str, AerosolType] = {t.name: t for t in (
    AerosolType("continental-clean", (("waso", 2600.0), ("inso", 0.15)), 8 * _KM, 2 * _KM),
    AerosolType("continental-average", (("waso", 7000.0), ("inso", 0.4), ("soot", 8300.0)), 8 * _KM, 2 * _KM),
    AerosolType("continental-polluted", (("waso", 15700.0), ("inso", 0.6), ("soot", 34300.0)), 8 * _KM, 2 * _KM),
    AerosolType("urban", (("waso", 28000.0), ("inso", 1.5), ("soot", 130000.0)), 8 * _KM, 2 * _KM),
    AerosolType("desert", (("waso", 2000.0), ("minm", 269.5), ("miam", 30.5), ("micm", 0.142)), 2 * _KM, 6 * _KM),
    AerosolType("maritime-clean", (("waso", 1500.0), ("ssam", 20.0), ("sscm", 3.2e-3)), 1 * _KM, 2 * _KM),
    AerosolType("maritime-polluted", (("waso", 3800.0), ("soot", 5180.0), ("ssam", 20.0), ("sscm", 3.2e-3)),
                1 * _KM, 2 * _KM),
    AerosolType("maritime-tropical", (("waso", 590.0), ("ssam", 10.0), ("sscm", 1.3e-3)), 1 * _KM, 2 * _KM),
    AerosolType("arctic", (("waso", 1300.0), ("inso", 0.01), ("soot", 5300.0), ("ssam", 1.9)), 99 * _KM, 2 * _KM),
    AerosolType("antarctic", (("suso", 42.9), ("ssam", 0.047), ("mitr", 0.0053)), 8 * _KM, 10 * _KM),
)}


@cache
def _component_rows(code: str) -> dict[str, NDArray[np.float64]]:
    if code not in OPAC_COMPONENTS:
        raise InvalidParameterError(f"unknown OPAC component {code!r}; known: {', '.join(OPAC_COMPONENTS)}")
    t = load_table("opac_components")
    sel = t["component_id"] == OPAC_COMPONENTS.index(code) + 1
    return {k: v[sel] for k, v in t.items()}


def _humidity(relative_humidity: Any) -> float:
    try:
        rh = float(relative_humidity)
    except (TypeError, ValueError):
        raise InvalidParameterError(
            f"relative humidity must be a number in [0, 99] %; got {relative_humidity!r}") from None
    if not (math.isfinite(rh) and 0.0 <= rh <= 99.0):
        raise InvalidParameterError(
            f"relative humidity must be in [0, 99] % (OPAC's range); got {relative_humidity!r}")
    return rh


@cache
def opac_component(code: str, relative_humidity: float = 0.0):
    """``(LogNormalMode, RefractiveIndex)`` of an OPAC component at a relative humidity [%] in [0, 99].

    Radii in metres. Non-hygroscopic components are the same at every humidity; for the hygroscopic ones the mode
    radius, the radius limits and the refractive index are interpolated linearly in humidity between OPAC's
    classes (0, 50, 70, 80, 90, 95, 98, 99 %).
    """
    from .refractive_index import RefractiveIndex
    from .size_distributions import LogNormalMode

    rows = _component_rows(code)
    rh = _humidity(relative_humidity)
    classes = np.unique(rows["rh_percent"])
    if classes.size == 1:
        lo = hi = float(classes[0])
        t = 0.0
    else:
        j = int(np.clip(np.searchsorted(classes, rh, side="right") - 1, 0, classes.size - 2))
        lo, hi = float(classes[j]), float(classes[j + 1])
        t = (rh - lo) / (hi - lo)

    def at(cls_rh: float) -> dict[str, NDArray[np.float64]]:
        sel = rows["rh_percent"] == cls_rh
        return {k: v[sel] for k, v in rows.items()}

    a, b = at(lo), at(hi)

    def mix(key: str) -> NDArray[np.float64]:
        return (1.0 - t) * a[key] + t * b[key]

    um = 1e-6
    mode = LogNormalMode(float(mix("r_mod_um")[0]) * um, float(a["sigma"][0]), float(mix("r_min_um")[0]) * um,
                         float(mix("r_max_um")[0]) * um)
    index = RefractiveIndex(tuple(a["wavelength_nm"]), tuple(mix("n_real")), tuple(mix("n_imag")),
                            f"OPAC {_COMPONENT_NAMES[code]} at {rh:g} % RH")
    return mode, index


def _aerosol_type(name: str) -> AerosolType:
    try:
        return AEROSOL_TYPES[name]
    except KeyError:
        raise InvalidParameterError(
            f"unknown aerosol type {name!r}; known: {', '.join(AEROSOL_TYPES)}") from None


@register_particle_kind
@dataclass(frozen=True)
class OpacAerosol(ParticleComponent):
    """An external mixture of OPAC components with Mie optics (module docstring).

    Parameters
    ----------
    name : str
        Label (an aerosol type's name for :meth:`preset`).
    components : tuple of (str, float)
        OPAC component code and its number density at relative density 1 [cm^-3].
    density : DensityProfile
        Relative density of the whole mixture.
    relative_humidity : float
        [%] in [0, 99] (default 50).
    optical_depth_550 : float or None
        Vertical optical depth at 550 nm, >= 0: the number densities are scaled to give it (their ratios are
        kept). None (default): the number densities are absolute.
    column_height : float
        Height [m] to which the optical depth is counted (default 60 km, the top of the default atmosphere).
    nodes_per_e : float
        Radius nodes per unit of ln r of the Mie integrals (:mod:`.size_distributions`).
    """

    kind: ClassVar[str] = "opac"
    name: str
    components: tuple[tuple[str, float], ...]
    density: DensityProfile = field(default_factory=lambda: AEROSOL_TYPES["continental-average"].profile())
    relative_humidity: float = 50.0
    optical_depth_550: float | None = None
    column_height: float = 60_000.0
    nodes_per_e: float = 24.0

    def __post_init__(self) -> None:
        if not isinstance(self.density, DensityProfile):
            raise InvalidParameterError(f"aerosol {self.name!r}: density must be a DensityProfile")
        comps = []
        try:
            items = tuple(self.components)
        except TypeError:
            raise InvalidParameterError("aerosol components must be (code, number density) pairs") from None
        if not items:
            raise InvalidParameterError(f"aerosol {self.name!r} needs at least one component")
        for item in items:
            try:
                code, number = item
                number = float(number)
            except (TypeError, ValueError):
                raise InvalidParameterError(
                    f"aerosol components must be (code, number density [cm^-3]) pairs; got {item!r}") from None
            if code not in OPAC_COMPONENTS:
                raise InvalidParameterError(f"unknown OPAC component {code!r}; known: {', '.join(OPAC_COMPONENTS)}")
            if not (math.isfinite(number) and number >= 0):
                raise InvalidParameterError(f"number density of {code} must be >= 0 cm^-3; got {number!r}")
            comps.append((str(code), number))
        if sum(n for _, n in comps) <= 0:
            raise InvalidParameterError(f"aerosol {self.name!r}: the number densities are all zero")
        object.__setattr__(self, "components", tuple(comps))
        object.__setattr__(self, "relative_humidity", _humidity(self.relative_humidity))
        if self.optical_depth_550 is not None:
            try:
                tau = float(self.optical_depth_550)
            except (TypeError, ValueError):
                raise InvalidParameterError(
                    f"optical depth must be a number >= 0; got {self.optical_depth_550!r}") from None
            if not (math.isfinite(tau) and 0.0 <= tau <= 10.0):
                raise InvalidParameterError(f"aerosol optical depth at 550 nm must be in [0, 10]; got {tau!r}")
            object.__setattr__(self, "optical_depth_550", tau)
        h = float(self.column_height)
        if not (math.isfinite(h) and h > 0):
            raise InvalidParameterError(f"column height must be > 0 m; got {self.column_height!r}")
        object.__setattr__(self, "column_height", h)
        if self.density.column(h) <= 0:
            raise InvalidParameterError(f"aerosol {self.name!r}: its density profile is zero everywhere")
        if not (math.isfinite(float(self.nodes_per_e)) and float(self.nodes_per_e) >= 2):
            raise InvalidParameterError("nodes_per_e must be >= 2")

    @classmethod
    def preset(cls, name: str, optical_depth_550: float | None = None, relative_humidity: float = 50.0,
               column_height: float = 60_000.0) -> OpacAerosol:
        """The OPAC aerosol type ``name`` (:data:`AEROSOL_TYPES`) with its profile, optionally rescaled to a
        vertical optical depth at 550 nm; ``relative_humidity`` [%]."""
        t = _aerosol_type(name)
        return cls(t.name, t.components, t.profile(), relative_humidity, optical_depth_550, column_height)

    @classmethod
    def mixture(cls, members: Any, relative_humidity: float = 50.0, density: DensityProfile | None = None,
                column_height: float = 60_000.0) -> OpacAerosol:
        """An external mixture of OPAC components and types, each with its own vertical optical depth at 550 nm.

        Parameters
        ----------
        members : sequence of (str, float)
            An OPAC component code (:data:`OPAC_COMPONENTS`, e.g. ``"waso"`` fine, ``"sscm"`` coarse) or an
            aerosol type's name (:data:`AEROSOL_TYPES`, its components in their Table 4 ratios) and the optical
            depth [-] >= 0 at 550 nm it contributes; at least one > 0. The mixture's optical depth is their sum
            (extinction adds over an external mixture, Hess et al. 1998, Eq. 1).
        relative_humidity : float
            [%] in [0, 99].
        density : DensityProfile, optional
            The mixture's profile (default: that of the first member that is a type, else that of
            continental-average).
        column_height : float
            Height [m] to which the optical depths are counted (default 60 km).
        """
        try:
            items = [(str(m), float(t)) for m, t in members]
        except (TypeError, ValueError):
            raise InvalidParameterError("mixture members must be (component or type, optical depth) pairs") from None
        if not items or len({m for m, _ in items}) != len(items):
            raise InvalidParameterError("a mixture needs one or more distinct members")
        for m, tau in items:
            if m not in OPAC_COMPONENTS and m not in AEROSOL_TYPES:
                raise InvalidParameterError(f"unknown mixture member {m!r}; OPAC components: "
                                            f"{', '.join(OPAC_COMPONENTS)}; types: {', '.join(AEROSOL_TYPES)}")
            if not (math.isfinite(tau) and 0.0 <= tau <= 10.0):
                raise InvalidParameterError(f"optical depth of {m} must be in [0, 10]; got {tau!r}")
        if density is None:
            types = [AEROSOL_TYPES[m] for m, _ in items if m in AEROSOL_TYPES]
            density = (types[0] if types else AEROSOL_TYPES["continental-average"]).profile()
        column = density.column(float(column_height))
        rh = _humidity(relative_humidity)
        numbers: dict[str, float] = {}
        for m, tau in items:
            comps = AEROSOL_TYPES[m].components if m in AEROSOL_TYPES else ((m, 1.0),)
            unit = column * sum(n * 1e6 * _extinction_550(code, rh, 24.0) for code, n in comps)
            for code, n in comps:
                numbers[code] = numbers.get(code, 0.0) + n * tau / unit
        return cls("+".join(m for m, _ in items), tuple(numbers.items()), density, rh, None, column_height)

    # ------------------------------------------------------------------ optics

    def component_optics(self, wavelengths: ArrayLike):
        """``[(code, number density [m^-3] at relative density 1, MieOptics)]`` after the optical-depth scaling."""
        from .mie_optics import stored_mie_optics

        wl = np.asarray(wavelengths, dtype=float)
        scale = self._scale()
        out = []
        for code, number in self.components:
            mode, index = opac_component(code, self.relative_humidity)
            out.append((code, number * 1e6 * scale, stored_mie_optics(mode, index, wl, nodes_per_e=self.nodes_per_e)))
        return out

    def _scale(self) -> float:
        if self.optical_depth_550 is None:
            return 1.0
        return _optical_depth_scale(self)

    def extinction_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        return sum(n * o.extinction_cross_section for _, n, o in self.component_optics(wavelengths))

    def scattering_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        return sum(n * o.scattering_cross_section for _, n, o in self.component_optics(wavelengths))

    def single_scattering_albedo_at(self, wavelengths: ArrayLike) -> NDArray[np.float64]:
        optics = self.component_optics(wavelengths)
        ext = sum(n * o.extinction_cross_section for _, n, o in optics)
        sca = sum(n * o.scattering_cross_section for _, n, o in optics)
        return np.where(ext > 0, sca / np.where(ext > 0, ext, 1.0), 1.0)

    def phase_table(self, wavelengths: ArrayLike, angles: ArrayLike | None = None) -> PhaseTable:
        from ..spectral import as_wavelengths
        from .mie_optics import stored_mie_optics

        # the components' own number densities: the phase does not depend on the optical-depth scaling, which
        # may be 0 (an aerosol-free node of a table family)
        wl = as_wavelengths(wavelengths)
        optics = [(n, stored_mie_optics(mode, index, wl, nodes_per_e=self.nodes_per_e))
                  for code, n in self.components if n > 0
                  for mode, index in [opac_component(code, self.relative_humidity)]]
        table = PhaseTable.mixture([o.phase for _, o in optics],
                                   np.stack([n * o.scattering_cross_section for n, o in optics]))
        return table if angles is None else table.on_angles(angles)

    # ------------------------------------------------------------------ serialisation

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "name": self.name, "components": [list(c) for c in self.components],
                "density": self.density.to_dict(), "relative_humidity": self.relative_humidity,
                "optical_depth_550": self.optical_depth_550, "column_height": self.column_height,
                "nodes_per_e": self.nodes_per_e}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> OpacAerosol:
        return cls(data["name"], tuple((c[0], float(c[1])) for c in data["components"]),
                   DensityProfile.from_dict(data["density"]), float(data["relative_humidity"]),
                   data.get("optical_depth_550"), float(data.get("column_height", 60_000.0)),
                   float(data.get("nodes_per_e", 24.0)))


def _extinction_550(code: str, relative_humidity: float, nodes_per_e: float) -> float:
    """Extinction cross-section [m^2] of one particle of an OPAC component at 550 nm."""
    from .mie_optics import stored_mie_optics

    mode, index = opac_component(code, relative_humidity)
    return float(stored_mie_optics(mode, index, [550.0], nodes_per_e=nodes_per_e).extinction_cross_section[0])


def _optical_depth_scale(aerosol: OpacAerosol) -> float:
    ext = sum(number * 1e6 * _extinction_550(code, aerosol.relative_humidity, aerosol.nodes_per_e)
              for code, number in aerosol.components)
    tau = ext * aerosol.density.column(aerosol.column_height)
    return float(aerosol.optical_depth_550) / tau
