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

import dataclasses
import importlib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..atmosphere.options import ATMOSPHERE_OPTIONS, atmosphere_option
from ..conventions import MAX_EXTRATERRESTRIAL_ILLUMINANCE, MAX_EXTRATERRESTRIAL_IRRADIANCE, MAX_SKY_LUMINANCE
from ..deprecation import rename
from ..errors import InvalidParameterError
from ..references import cite
from ..validation import Parameter

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


def _encode(p: Parameter, value: Any) -> Any:
    """Plain JSON-able form of a parameter's value (atmospheres through their ``to_dict``)."""
    if value is None:
        return None
    if p.kind == "atmosphere":
        return _encode_atmosphere(value)
    if p.kind == "object":
        if not hasattr(value, "to_dict"):
            raise InvalidParameterError(f"{p.name}: a {type(value).__name__} cannot be described as data")
        cls = type(value)
        return {"class": f"{cls.__module__}:{cls.__qualname__}", "data": value.to_dict()}
    if p.kind == "float":
        return float(value)
    if p.kind == "int":
        return int(value)
    return value


def _decode(p: Parameter, value: Any) -> Any:
    """Inverse of :func:`_encode`."""
    if value is None or p.kind not in ("atmosphere", "object"):
        return value
    if p.kind == "object":
        if not isinstance(value, Mapping) or not str(value.get("class", "")).startswith("skyscatter."):
            raise InvalidParameterError(f"{p.name}: expected an encoded skyscatter object")
        module, _, name = value["class"].partition(":")
        return getattr(importlib.import_module(module), name).from_dict(value["data"])
    return _decode_atmosphere(p.name, value)


def _encode_atmosphere(value: Any) -> dict[str, Any]:
    """AtmosphereParameters -> its dict; precomputed tables -> their parameters plus the table settings."""
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
    renamed : mapping
        Old parameter name -> new one: the old spelling is still read (by :func:`build` and :func:`from_dict`,
        so saved skies load) with a DeprecationWarning, for one release.
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
    renamed: Mapping[str, str] = field(default_factory=dict)

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
    given = rename({k: v for k, v in parameters.items() if v is not None}, spec.renamed, spec.name)
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
    raw = rename(dict(raw), spec.renamed, f"{spec.name} sky dictionary")
    kwargs = {k: _decode(spec.parameter(k), v) for k, v in raw.items()}
    return build(spec.name, data.get("sun_zenith"), data.get("sun_azimuth"), **kwargs)


def to_dict(sky: SkyModel) -> dict[str, Any]:
    """Plain JSON-able description of a registered sky (what ``sky.to_dict()`` returns)."""
    spec = spec_for(sky)
    values = sky.model_parameters()
    out: dict[str, Any] = {"version": DICT_VERSION, "model": spec.name}
    if spec.uses_sun:
        out["sun_zenith"] = float(sky.sun_zenith)  # type: ignore[attr-defined]
        out["sun_azimuth"] = float(sky.sun_azimuth)  # type: ignore[attr-defined]
    out["parameters"] = {k: _encode(spec.parameter(k), v) for k, v in values.items() if v is not None}
    return out


# ------------------------------------------------------------------------------------------ the built-in models

_SUN_LIMIT = "the extraterrestrial solar value at perihelion, which nothing at the ground exceeds"
_TURBIDITY_HELP = "atmospheric turbidity T (haze + molecules over molecules alone)"
_SCALE = (
    Parameter("zenith_luminance", "cd m^-2", None, "zenith luminance (default: 10000 lx diffuse)",
              low=0.0, high=MAX_SKY_LUMINANCE, why="the luminance of the solar disc outside the atmosphere, which no "
              "part of the sky exceeds"),
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
        Parameter("turbidity", "1", 3.0, "turbidity of the published model", low=1.0, high=10.0,
                  why="the range of the published data"),
        Parameter("ground_albedo", "1", 0.1, "albedo of the atmosphere's ground, the same at every wavelength",
                  low=0.0, high=1.0, why="the range of the published data"),
        Parameter("dataset", "", None, "fitted coefficients (skyscatter.fit) instead of the published ones",
                  kind="object", cli=False),
    ),
    renamed={"albedo": "ground_albedo"},
    spectral=True,
))
register(ModelSpec(
    name="bruneton",
    factory="skyscatter.sky.bruneton:BrunetonSky",
    summary="Bruneton & Neyret 2008 precomputed multiple scattering, from the ground to orbit",
    citation=cite("Bruneton2008"),
    parameters=(
        Parameter("altitude", "m", 0.0, "observer altitude above the ground, from the ground to orbit", low=0.0,
                  high=1e8, why="a quarter of the way to the Moon; the tables resolve nothing finer there"),
        *(atmosphere_option(p.name) for p in ATMOSPHERE_OPTIONS),
        Parameter("tables", "", None, "which tables to build: spectral (default: 16 wavelengths, 400-700 nm, right "
                  "colour) or rgb (3: quicker to build, wrong colour at low sun)", kind="choice",
                  choices=("spectral", "rgb")),
        Parameter("atmosphere", "", None, "the atmosphere (AtmosphereParameters; default: the Earth defaults)",
                  kind="atmosphere", cli=False),
        Parameter("precomputed", "", None, "precomputed tables (PrecomputedAtmosphere) instead of the atmosphere",
                  kind="atmosphere", cli=False),
    ),
    renamed={"albedo": "ground_albedo", "wavelengths": "tables"},
    sun_below_horizon=True,
    spectral=True,
    cost="tables",
))
def cloud_layer_parameters(optical_depth: Parameter, highest: float) -> tuple[Parameter, ...]:
    """The parameters of one uniform water cloud layer (:class:`skyscatter.atmosphere.clouds.CloudLayer`), shared
    by the models that take one: its optical depth (``optical_depth``: each model its default and range), base and
    top altitudes [m] up to ``highest``, and the droplets' effective radius (the range of the droplet optics)."""
    return (
        optical_depth,
        Parameter("cloud_base", "m", 1000.0, "altitude of the cloud layer's base", low=0.0, high=highest),
        Parameter("cloud_top", "m", 1500.0, "altitude of the cloud layer's top (above its base)", low=0.0,
                  high=highest),
        Parameter("cloud_effective_radius", "m", 10e-6, "effective radius of the cloud droplets (Mie optics)",
                  low=1e-6, high=50e-6, why="the range of the droplet optics"),
    )


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
        *cloud_layer_parameters(Parameter("cloud_optical_depth", "1", 0.0, "optical depth at 550 nm of a uniform "
                                          "water cloud layer (0: none)", low=0.0, high=1000.0), highest=1e5),
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
        *cloud_layer_parameters(Parameter("cloud_optical_depth", "1", 15.0, "optical depth at 550 nm of a uniform "
                                          "water cloud layer (0: none; 15 a stratus)", low=0.0, high=60.0,
                                          why="the range measured against the Monte Carlo"), highest=20000.0),
        Parameter("ground_albedo", "1", None, "ground albedo, the same at every wavelength (default 0.1)", low=0.0,
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

register(ModelSpec(
    name="broken-cloud",
    factory="skyscatter.sky.broken_cloud:BrokenCloudSky",
    summary="broken 3D cloud fields (procedural by cover, or a NetCDF/Zarr field) ray-marched in the precomputed "
            "clear sky",
    citation=cite("Wrenninge2013", "Bruneton2008",
                  note="Ray marching with the multiple-scattering octaves of the first (fitted to the Monte Carlo) "
                       "in the clear sky of the second:"),
    parameters=(
        Parameter("cloud_cover", "1", 0.5, "procedural field: fraction of the columns that hold cloud", low=0.0,
                  high=1.0, why="a fraction"),
        Parameter("cloud_seed", "1", 0, "procedural field: seed of its noise", kind="int", low=0, high=2**32 - 1),
        Parameter("cloud_optical_depth", "1", 10.0, "procedural field: mean optical depth at 550 nm of its cloudy "
                  "columns", low=0.0, high=100.0, low_open=True),
        Parameter("cloud_base", "m", 1000.0, "procedural field: altitude of the cloud base", low=0.0, high=20000.0),
        Parameter("cloud_top", "m", 2500.0, "procedural field: altitude of the highest cloud tops (above the base)",
                  low=0.0, high=20000.0),
        Parameter("cloud_effective_radius", "m", 10e-6, "effective radius of the cloud droplets (Mie optics)",
                  low=1e-6, high=50e-6, why="the range of the droplet optics"),
        Parameter("cloud_field", "", None, "a cloud field file (NetCDF .nc or Zarr .zarr: variable extinction "
                  "[m^-1 at 550 nm] on (x, y, z), attributes base and top [m]) instead of the procedural field",
                  kind="path"),
        Parameter("clouds", "", None, "a 3D cloud field (skyscatter.atmosphere.clouds.CloudField)", kind="object",
                  cli=False),
        Parameter("altitude", "m", 0.0, "observer altitude above the ground: below, in or above the clouds",
                  low=0.0, high=1e8),
        Parameter("ground_albedo", "1", None, "ground albedo, the same at every wavelength (default 0.1)", low=0.0,
                  high=1.0),
        Parameter("atmosphere", "", None, "the air (AtmosphereParameters; default: the Earth defaults)",
                  kind="atmosphere", cli=False),
        Parameter("interpolation", "", "linear", "densities between voxel centres: linear (smooth edges) or voxel "
                  "(constant per voxel, as the Monte Carlo)", kind="choice", choices=("linear", "voxel"), cli=False),
    ),
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
