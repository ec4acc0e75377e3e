"""The sky-model registry: every model described once, by a frozen :class:`ModelSpec`.

A spec names the model, the class that implements it (imported only when a model is built, so listing the
models stays cheap), its parameters with unit, default and valid range, and the publication it implements.
From the specs come

* construction by name: :func:`build` (``registry.build("preetham", sun_zenith, sun_azimuth, turbidity=3)``);
* serialisation: ``sky.to_dict()`` gives plain JSON-able data and :func:`from_dict` rebuilds an identical sky
  (pickling goes through the same pair, so Dask can ship skies to workers);
* the command-line options of ``skyscatter sky``, ``illuminance`` and ``demo`` (:mod:`skyscatter.cli.sky_options`);
* the conformance suite that every registered model passes (``tests/test_conformance.py``).

Adding a model is one module in :mod:`skyscatter.sky` plus one :func:`register` call below (or from the
caller's own package, for a model that lives outside skyscatter).
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..conventions import MAX_EXTRATERRESTRIAL_ILLUMINANCE, MAX_EXTRATERRESTRIAL_IRRADIANCE, check_daylight_limit
from ..errors import InvalidParameterError
from ..references import cite

if TYPE_CHECKING:
    from .base import SkyModel

__all__ = [
    "ModelSpec",
    "Parameter",
    "SKY_MODELS",
    "build",
    "build_sky",
    "from_dict",
    "get",
    "models",
    "register",
    "spec_for",
]

#: Version of the dictionary layout written by ``SkyModel.to_dict``.
DICT_VERSION = 1


def _aerosol_types() -> tuple[str, ...]:
    from ..atmosphere.aerosol_types import AEROSOL_TYPES

    return tuple(AEROSOL_TYPES)


@dataclass(frozen=True)
class Parameter:
    """One parameter of a sky model (a keyword argument of its class).

    Attributes
    ----------
    name : str
        Keyword name in the Python API.
    unit : str
        SI unit, ``"1"`` for dimensionless numbers, ``""`` for non-numeric values.
    default : Any
        Value used when the parameter is not given (None: optional, the model decides).
    help : str
        One line for documentation and ``--help``.
    kind : {"float", "int", "bool", "choice", "path", "atmosphere", "object"}
        Value type (``"path"``: a file name). ``"atmosphere"`` is an
        :class:`~skyscatter.atmosphere.AtmosphereParameters` or precomputed
        tables (serialised through the parameters' ``to_dict``); ``"object"`` a skyscatter object with
        ``to_dict`` / ``from_dict`` (such as a fitted dataset).
    low, high : float or None
        Inclusive valid range of numeric values (None: unbounded on that side).
    choices : tuple
        Allowed values of a ``"choice"`` parameter.
    flag : str or None
        Command-line flag; default ``--name-with-dashes``. ``cli=False`` keeps the parameter out of the CLI.
    low_open : bool
        True when ``low`` itself is excluded (the value must be greater than ``low``).
    why : str
        Where the range comes from (a physical limit, the publication's validity), quoted in error messages.
    """

    name: str
    unit: str
    default: Any = None
    help: str = ""
    kind: str = "float"
    low: float | None = None
    high: float | None = None
    choices: tuple = ()
    flag: str | None = None
    cli: bool = True
    low_open: bool = False
    why: str = ""

    @property
    def cli_flag(self) -> str:
        return self.flag or "--" + self.name.replace("_", "-")

    def range_text(self, *, with_unit: bool = True) -> str:
        """Human-readable valid range with unit, e.g. ``"1.65 to 11"`` or ``">= 0 lx"``."""
        unit = "" if self.unit in ("1", "") or not with_unit else f" {self.unit}"
        if self.kind == "choice":
            return "one of " + ", ".join(map(str, self.choices))
        if self.low is not None and self.high is not None:
            return f"{'above ' if self.low_open else ''}{self.low:g} to {self.high:g}{unit}"
        if self.low is not None:
            return f"{'>' if self.low_open else '>='} {self.low:g}{unit}"
        if self.high is not None:
            return f"<= {self.high:g}{unit}"
        return f"any finite value{unit}" if self.kind in ("float", "int") else ""

    def check(self, value: Any, model: str, *, ranges: bool = True) -> Any:
        """Validate one value (type, finiteness and, with ``ranges``, the range); return it converted.

        The model classes enforce their ranges themselves (some have documented escape hatches, such as
        ``PreethamSky(strict=False)``); the command line checks the ranges here first so that it can refuse a value
        before any work, and the conformance suite checks that spec and class agree.
        """
        if value is None:
            return None
        where = f"{model}: {self.name}"
        if self.kind in ("float", "int"):
            if isinstance(value, bool) or isinstance(value, str):
                raise InvalidParameterError(f"{where} must be a number [{self.unit}]; got {value!r}")
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise InvalidParameterError(f"{where} must be a number [{self.unit}]; got {value!r}") from None
            if not math.isfinite(number):
                raise InvalidParameterError(f"{where} must be finite; got {value!r}")
            if self.kind == "int":
                if number != int(number):
                    raise InvalidParameterError(f"{where} must be a whole number; got {value!r}")
                number = int(number)
            below = self.low is not None and (number <= self.low if self.low_open else number < self.low)
            outside = below or (self.high is not None and number > self.high)
            if ranges and outside:
                if self.high is not None and number > self.high:
                    check_daylight_limit(self.name, number, self.unit)  # the physical limit, named with its source
                reason = f" ({self.why})" if self.why else ""
                unit = "" if self.unit in ("1", "") else f" {self.unit}"
                raise InvalidParameterError(f"{where} {number:g}{unit} is outside {self.range_text()}{reason}")
            return number
        if self.kind == "bool":
            if not isinstance(value, bool):
                raise InvalidParameterError(f"{where} must be True or False; got {value!r}")
            return value
        if self.kind == "choice":
            if value not in self.choices:
                raise InvalidParameterError(f"{where} must be {self.range_text()}; got {value!r}")
            return value
        if self.kind == "path":
            if not isinstance(value, str) or not value:
                raise InvalidParameterError(f"{where} must be a file name; got {value!r}")
            return value
        return value

    def encode(self, value: Any) -> Any:
        """Plain JSON-able form of a value (atmospheres through their ``to_dict``)."""
        if value is None:
            return None
        if self.kind == "atmosphere":
            return _encode_atmosphere(value)
        if self.kind == "object":
            if not hasattr(value, "to_dict"):
                raise InvalidParameterError(f"{self.name}: a {type(value).__name__} cannot be described as data")
            cls = type(value)
            return {"class": f"{cls.__module__}:{cls.__qualname__}", "data": value.to_dict()}
        if self.kind == "float":
            return float(value)
        if self.kind == "int":
            return int(value)
        return value

    def decode(self, value: Any) -> Any:
        """Inverse of :meth:`encode`."""
        if value is None or self.kind not in ("atmosphere", "object"):
            return value
        if self.kind == "object":
            if not isinstance(value, Mapping) or not str(value.get("class", "")).startswith("skyscatter."):
                raise InvalidParameterError(f"{self.name}: expected an encoded skyscatter object")
            module, _, name = value["class"].partition(":")
            return getattr(importlib.import_module(module), name).from_dict(value["data"])
        return _decode_atmosphere(self.name, value)


def _encode_atmosphere(value: Any) -> dict[str, Any]:
    """AtmosphereParameters -> its dict; precomputed tables -> their parameters plus the table settings."""
    import dataclasses

    from ..atmosphere import AtmosphereParameters

    if isinstance(value, AtmosphereParameters):
        return {"atmosphere": value.to_dict()}
    return {"atmosphere": value.parameters.to_dict(), "orders": int(value.orders),
            "wavelengths": [float(w) for w in value.wavelengths], "sizes": dataclasses.asdict(value.sizes)}


def _decode_atmosphere(name: str, value: Any) -> Any:
    """Inverse of :func:`_encode_atmosphere`; tables come from the table cache (computed once if absent)."""
    from ..atmosphere import AtmosphereParameters

    if not isinstance(value, Mapping) or "atmosphere" not in value:
        raise InvalidParameterError(f"{name}: expected an encoded atmosphere, got {type(value).__name__}")
    params = AtmosphereParameters.from_dict(value["atmosphere"])
    if set(value) == {"atmosphere"}:
        return params
    from ..precomputed.cache import cached_atmosphere

    return cached_atmosphere(params, orders=value["orders"], wavelengths=value["wavelengths"], sizes=value["sizes"])


@dataclass(frozen=True)
class ModelSpec:
    """A sky model described once: name, implementation, parameters, citation.

    Attributes
    ----------
    name : str
        Registry name (``--model`` on the command line).
    factory : str
        ``"module:Class"``; the class is called as ``Class(sun_zenith=..., sun_azimuth=..., **parameters)``
        (without the sun angles when ``uses_sun`` is False).
    summary : str
        One line for ``--help``.
    citation : str
        The publication the model implements (with DOI where it has one).
    parameters : tuple of Parameter
    uses_sun : bool
        False for models independent of the sun position (the CIE overcast sky).
    sun_below_horizon : bool
        True when the model accepts a sun below the horizon (twilight).
    spectral : bool
        True when the spectra are computed (not a luminance times a fixed relative spectrum).
    cost : {"cheap", "tables", "expensive"}
        How costly an evaluation is; the conformance suite samples expensive models more sparsely.
    """

    name: str
    factory: str
    summary: str
    citation: str
    parameters: tuple[Parameter, ...] = ()
    uses_sun: bool = True
    sun_below_horizon: bool = False
    spectral: bool = False
    cost: str = "cheap"

    def parameter(self, name: str) -> Parameter:
        for p in self.parameters:
            if p.name == name:
                return p
        raise InvalidParameterError(
            f"{self.name} has no parameter {name!r}; its parameters are: "
            + (", ".join(p.name for p in self.parameters) or "none")
        )

    def model_class(self) -> type:
        module, _, cls = self.factory.partition(":")
        return getattr(importlib.import_module(module), cls)

    def defaults(self) -> dict[str, Any]:
        return {p.name: p.default for p in self.parameters if p.default is not None}


_REGISTRY: dict[str, ModelSpec] = {}


def register(spec: ModelSpec) -> ModelSpec:
    """Add a model (a name may be registered once; re-registering the same spec is a no-op)."""
    if not isinstance(spec, ModelSpec):
        raise InvalidParameterError(f"register() takes a ModelSpec; got {type(spec).__name__}")
    old = _REGISTRY.get(spec.name)
    if old is not None and old != spec:
        raise InvalidParameterError(f"a different sky model named {spec.name!r} is already registered")
    _REGISTRY[spec.name] = spec
    return spec


def models() -> Iterator[ModelSpec]:
    """The registered models' specs, in registration order."""
    return iter(tuple(_REGISTRY.values()))


def names() -> list[str]:
    return list(_REGISTRY)


def get(name: str) -> ModelSpec:
    """The spec of model ``name``; InvalidParameterError listing the models for an unknown name."""
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise InvalidParameterError(f"unknown sky model {name!r}; choose one of {', '.join(_REGISTRY)}") from None


def spec_for(model: SkyModel | type) -> ModelSpec:
    """The spec of a sky instance or class (looked up by the class's ``model_name``)."""
    cls = model if isinstance(model, type) else type(model)
    name = getattr(cls, "model_name", None)
    if name is None or name not in _REGISTRY:
        raise InvalidParameterError(f"{cls.__name__} is not a registered sky model")
    return _REGISTRY[name]


def build(name: str, sun_zenith: float | None = None, sun_azimuth: float | None = None, **parameters: Any) -> SkyModel:
    """Construct the registered model ``name`` for a sun at (zenith, azimuth) [rad] with its defaults.

    ``parameters`` are the model's keyword arguments (see ``get(name).parameters``); None values are dropped,
    unknown names raise :class:`~skyscatter.errors.InvalidParameterError`, and the rest are checked for type and
    finiteness here; the model class checks its ranges (with its own, more specific messages).
    """
    spec = get(name)
    given = {k: v for k, v in parameters.items() if v is not None}
    kwargs = spec.defaults()
    for key, value in given.items():
        kwargs[key] = spec.parameter(key).check(value, spec.name, ranges=False)
    if spec.uses_sun:
        if sun_zenith is None or sun_azimuth is None:
            raise InvalidParameterError(f"{spec.name} needs the sun position (sun_zenith, sun_azimuth) [rad]")
        kwargs["sun_zenith"] = sun_zenith
        kwargs["sun_azimuth"] = sun_azimuth
    return spec.model_class()(**kwargs)


def build_sky(name: str, sun_zenith: float, sun_azimuth: float, **options: Any) -> SkyModel:
    """Same as :func:`build` (the name used before the registry had specs)."""
    return build(name, sun_zenith, sun_azimuth, **options)


def from_dict(data: Mapping[str, Any]) -> SkyModel:
    """Rebuild a sky from ``sky.to_dict()``: same model, sun and parameters, so the same radiance."""
    if not isinstance(data, Mapping) or "model" not in data:
        raise InvalidParameterError("from_dict needs the mapping made by SkyModel.to_dict() (with a 'model' key)")
    version = data.get("version", DICT_VERSION)
    if version != DICT_VERSION:
        raise InvalidParameterError(f"sky dictionary version {version!r} is not supported (expected {DICT_VERSION})")
    spec = get(data["model"])
    raw = data.get("parameters", {}) or {}
    if not isinstance(raw, Mapping):
        raise InvalidParameterError("the 'parameters' entry of a sky dictionary must be a mapping")
    kwargs = {k: spec.parameter(k).decode(v) for k, v in raw.items()}
    return build(spec.name, data.get("sun_zenith"), data.get("sun_azimuth"), **kwargs)


def to_dict(sky: SkyModel) -> dict[str, Any]:
    """Plain JSON-able description of a registered sky (what ``sky.to_dict()`` returns)."""
    spec = spec_for(sky)
    values = sky.model_parameters()
    out: dict[str, Any] = {"version": DICT_VERSION, "model": spec.name}
    if spec.uses_sun:
        out["sun_zenith"] = float(sky.sun_zenith)  # type: ignore[attr-defined]
        out["sun_azimuth"] = float(sky.sun_azimuth)  # type: ignore[attr-defined]
    out["parameters"] = {k: spec.parameter(k).encode(v) for k, v in values.items() if v is not None}
    return out


# ------------------------------------------------------------------------------------------ the built-in models

_SUN_LIMIT = "the extraterrestrial solar value at perihelion, which nothing at the ground exceeds"
_TURBIDITY_HELP = "atmospheric turbidity T (haze + molecules over molecules alone)"
_SCALE = (
    Parameter("zenith_luminance", "cd m^-2", None, "zenith luminance (default: 10000 lx diffuse)",
              low=0.0),
    Parameter("diffuse_illuminance", "lx", None, "horizontal diffuse illuminance to scale the sky to", low=0.0,
              high=MAX_EXTRATERRESTRIAL_ILLUMINANCE, why=_SUN_LIMIT),
)
_SUN_ILLUMINANCE = Parameter(
    "sun_illuminance_normal", "lx", 0.0,
    "direct normal illuminance of the solar disc (0: the distribution describes the sky only)",
    low=0.0, high=MAX_EXTRATERRESTRIAL_ILLUMINANCE, why=_SUN_LIMIT, flag="--sun-illuminance",
)

register(ModelSpec(
    name="preetham",
    factory="skyscatter.sky.preetham:PreethamSky",
    summary="Preetham et al. 1999 analytic clear sky, spectral, with sun",
    citation=cite("Preetham1999"),
    parameters=(
        Parameter("turbidity", "1", 2.5, _TURBIDITY_HELP, low=1.65, high=11.0),
        Parameter("below_horizon", "", "zero", "radiance below the horizon: zero, or the horizon value",
                  kind="choice", choices=("zero", "horizon"), cli=False),
        Parameter("strict", "", True, "refuse turbidities outside 1.65-11 (False: extrapolate in 1-20 with a "
                  "warning)", kind="bool", cli=False),
    ),
    spectral=True,
))
register(ModelSpec(
    name="preetham-overcast",
    factory="skyscatter.sky.overcast_blend:PreethamOvercastBlendSky",
    summary="Preetham 1999 Sec. 5: the Preetham sky blended into the CIE overcast sky from T = 6 to 10",
    citation=cite("Preetham1999", note="Sec. 5 of"),
    parameters=(
        Parameter("turbidity", "1", 8.0, _TURBIDITY_HELP + "; blended into overcast from 6 to 10",
                  low=1.65, high=11.0),
        Parameter("blend_start", "1", 6.0, "turbidity where the overcast weight starts rising from 0", cli=False),
        Parameter("blend_end", "1", 10.0, "turbidity where the overcast weight reaches 1", cli=False),
    ),
    spectral=True,
))
register(ModelSpec(
    name="cie",
    factory="skyscatter.sky.cie:CIEStandardSky",
    summary="CIE S 011/E:2003 standard general sky, 15 types, luminance only",
    citation=cite("CIE2003"),
    parameters=(Parameter("sky_type", "1", 12, "CIE 2003 standard sky type (12: the CIE clear sky)", kind="int",
                          low=1, high=15), *_SCALE, _SUN_ILLUMINANCE),
))
register(ModelSpec(
    name="cie-overcast",
    factory="skyscatter.sky.cie:CIEOvercastSky",
    summary="CIE overcast sky (Moon & Spencer 1942), luminance only, no sun",
    citation=cite("MoonSpencer1942"),
    parameters=_SCALE,
    uses_sun=False,
))
register(ModelSpec(
    name="cie-clear",
    factory="skyscatter.sky.cie:CIEClearSky",
    summary="CIE 1973 clear sky (Kittler), luminance only",
    citation=cite("CIE1973", "Kittler1967"),
    parameters=(*_SCALE, _SUN_ILLUMINANCE),
))

# The sky condition of one hour (Perez et al. 1990): the parameters of every model built from it.
_SKY_CONDITION = (
    Parameter("epsilon", "1", None, "sky clearness epsilon (with --delta; default 6.5 with delta 0.15, a clear "
              "sky)", low=1.0),
    Parameter("delta", "1", None, "sky brightness delta (with --epsilon)", low=0.0),
    _SCALE[1],
    Parameter("direct_normal_irradiance", "W m^-2", None,
              "direct normal irradiance (with --dhi, instead of --epsilon/--delta); at most the solar constant",
              low=0.0, high=MAX_EXTRATERRESTRIAL_IRRADIANCE, why=_SUN_LIMIT, flag="--dni"),
    Parameter("diffuse_horizontal_irradiance", "W m^-2", None, "diffuse horizontal irradiance", low=0.0,
              high=MAX_EXTRATERRESTRIAL_IRRADIANCE, why=_SUN_LIMIT, flag="--dhi", low_open=True),
    Parameter("day_of_year", "1", None, "day of the year for the Sun-Earth distance (default: mean distance)",
              kind="int", low=1, high=366),
    Parameter("dew_point", "deg C", 11.0, "surface dew point for the luminous efficacies", low=-90.0, high=60.0),
    Parameter("guards", "", True, "apply Radiance gendaylit's guards on epsilon, delta and the sun zenith",
              kind="bool", cli=False),
)

register(ModelSpec(
    name="perez",
    factory="skyscatter.sky.perez:PerezSky",
    summary="Perez et al. 1993 all-weather sky (epsilon/delta or DNI/DHI), luminance only",
    citation=cite("Perez1993"),
    parameters=_SKY_CONDITION,
))
register(ModelSpec(
    name="asrc-cie",
    factory="skyscatter.sky.asrc_cie:ASRCCIESky",
    summary="ASRC-CIE sky: CIE clear, turbid, intermediate and overcast skies weighted by epsilon/delta "
            "(or DNI/DHI), luminance only",
    citation=cite("Perez1992", "EnergyPlusEngineering",
                  note="The model of the first, with the weights and components restated in the second:"),
    parameters=_SKY_CONDITION,
))
register(ModelSpec(
    name="hosek-wilkie",
    factory="skyscatter.sky.hosek_wilkie:HosekWilkieSky",
    summary="Hosek & Wilkie 2012 spectral clear sky (320-720 nm) with the 2013 solar disc",
    citation=cite("HosekWilkie2012", "HosekWilkie2013"),
    parameters=(
        Parameter("turbidity", "1", 3.0, "turbidity of the published model", low=1.0, high=10.0),
        Parameter("albedo", "1", 0.1, "ground albedo, the same at every wavelength", low=0.0, high=1.0),
        Parameter("dataset", "", None, "fitted coefficients (skyscatter.fit) instead of the published ones",
                  kind="object", cli=False),
    ),
    spectral=True,
))
register(ModelSpec(
    name="bruneton",
    factory="skyscatter.sky.bruneton:BrunetonSky",
    summary="Bruneton & Neyret 2008 precomputed multiple scattering, from the ground to orbit",
    citation=cite("Bruneton2008"),
    parameters=(
        Parameter("altitude", "m", 0.0, "observer altitude above the ground, from the ground to orbit", low=0.0,
                  high=1e8),
        Parameter("turbidity", "1", None, "aerosols from turbidity (Preetham 1999 A.1; default: the Earth "
                  "defaults' light aerosol)", low=1.0, high=20.0),
        Parameter("aerosol_optical_depth", "1", None, "vertical aerosol optical depth at 550 nm (instead of "
                  "--turbidity)", low=0.0, high=10.0, flag="--aod"),
        Parameter("angstrom_alpha", "1", None, "Angstrom exponent of the aerosol optical depth (with --aod; "
                  "default 1.3)", low=-1.0, high=4.0),
        Parameter("albedo", "1", None, "ground albedo, the same at every wavelength (default 0.1)", low=0.0,
                  high=1.0),
        Parameter("ozone_column", "DU", None, "total ozone column (default 300)", low=0.0, high=1000.0,
                  flag="--ozone"),
        Parameter("aerosol_type", "", None, "OPAC aerosol type with Mie optics (Hess et al. 1998; with --aod its "
                  "optical depth at 550 nm, else the type's own)", kind="choice", choices=_aerosol_types(),
                  flag="--aerosol"),
        Parameter("atmosphere_file", "", None, "the air from a JSON file (written by 'skyscatter fit-atmosphere' "
                  "or AtmosphereParameters.save_json); the other options change it", kind="path",
                  flag="--atmosphere"),
        Parameter("wavelengths", "", None, "table wavelengths: spectral (default: 16, 400-700 nm, right colour) "
                  "or rgb (3: quicker to build, wrong colour at low sun)", kind="choice", choices=("spectral", "rgb")),
        Parameter("atmosphere", "", None, "the atmosphere (AtmosphereParameters or precomputed tables; default: "
                  "the Earth defaults)", kind="atmosphere", cli=False),
    ),
    sun_below_horizon=True,
    spectral=True,
    cost="tables",
))
register(ModelSpec(
    name="montecarlo",
    factory="skyscatter.sky.montecarlo:MonteCarloSky",
    summary="spectral Monte Carlo reference: all orders of scattering in the spherical atmosphere (slow)",
    citation=cite("HosekWilkie2012", "Wilkie2014",
                  note="Brute-force spectral path tracing (as in Sec. 3 of the first) with next-event estimation "
                       "and hero wavelengths (the second):"),
    parameters=(
        Parameter("altitude", "m", 0.0, "observer altitude above the ground", low=0.0, high=1e8),
        Parameter("samples", "1", 1024, "paths per direction (the standard error falls as 1/sqrt(samples))",
                  kind="int", low=1, high=1e8),
        Parameter("seed", "1", 0, "seed of the counter-based random streams", kind="int", low=0, high=2**63 - 1),
        Parameter("atmosphere", "", None, "the medium (AtmosphereParameters; default: the Earth defaults)",
                  kind="atmosphere", cli=False),
        Parameter("cloud_optical_depth", "1", 0.0, "optical depth at 550 nm of a uniform water cloud layer (0: none)",
                  low=0.0, high=1000.0),
        Parameter("cloud_base", "m", 1000.0, "altitude of the cloud layer's base", low=0.0, high=1e5),
        Parameter("cloud_top", "m", 1500.0, "altitude of the cloud layer's top (above its base)", low=0.0, high=1e5),
        Parameter("cloud_effective_radius", "m", 10e-6, "effective radius of the cloud droplets (Mie optics)",
                  low=1e-6, high=50e-6),
        Parameter("clouds", "", None, "a 3D cloud field (skyscatter.atmosphere.clouds.CloudField)", kind="object",
                  cli=False),
    ),
    sun_below_horizon=True,
    spectral=True,
    cost="expensive",
))

register(ModelSpec(
    name="cloudy",
    factory="skyscatter.sky.cloudy:CloudySky",
    summary="overcast and layered clouds: a uniform water cloud layer in the air, solved by DISORT (fast)",
    citation=cite("Stamnes1988", "NakajimaTanaka1988",
                  note="The medium's layers (air, Mie cloud droplets) solved by the discrete-ordinate method of the "
                       "first with the intensity correction of the second:"),
    parameters=(
        Parameter("cloud_optical_depth", "1", 15.0, "optical depth at 550 nm of a uniform water cloud layer "
                  "(0: none; 15 a stratus)", low=0.0, high=60.0, why="the range measured against the Monte Carlo"),
        Parameter("cloud_base", "m", 1000.0, "altitude of the cloud layer's base", low=0.0, high=20000.0),
        Parameter("cloud_top", "m", 1500.0, "altitude of the cloud layer's top (above its base)", low=0.0,
                  high=20000.0),
        Parameter("cloud_effective_radius", "m", 10e-6, "effective radius of the cloud droplets (Mie optics)",
                  low=1e-6, high=50e-6, why="the range of the droplet optics"),
        Parameter("albedo", "1", None, "ground albedo, the same at every wavelength (default 0.1)", low=0.0,
                  high=1.0),
        Parameter("altitude", "m", 0.0, "observer altitude above the ground: below, in or above the clouds",
                  low=0.0, high=1e8),
        Parameter("streams", "1", 16, "DISORT streams (even)", kind="int", low=4, high=64, cli=False),
        Parameter("illumination", "", "tables", "light on the cloud top: tables (the precomputed clear sky, "
                  "spherical) or column (the whole air in DISORT)", kind="choice", choices=("tables", "column"),
                  cli=False),
        Parameter("atmosphere", "", None, "the air (AtmosphereParameters; default: the Earth defaults)",
                  kind="atmosphere", cli=False),
    ),
    sun_below_horizon=True,
    spectral=True,
    cost="tables",
))


class _Summaries(Mapping):
    """``SKY_MODELS``: read-only name -> one-line summary view of the registry (kept for older callers)."""

    def __getitem__(self, key: str) -> str:
        return get(key).summary

    def __iter__(self) -> Iterator[str]:
        return iter(list(_REGISTRY))

    def __len__(self) -> int:
        return len(_REGISTRY)


#: name -> one-line description of every registered model.
SKY_MODELS: Mapping[str, str] = _Summaries()
