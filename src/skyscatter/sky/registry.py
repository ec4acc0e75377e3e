"""Sky models by name, as the command line and batch jobs choose them."""

from __future__ import annotations

from typing import Any

from ..errors import InvalidParameterError
from .base import SkyModel

__all__ = ["SKY_MODELS", "build_sky"]

#: name -> one-line description (shown by ``skyscatter sky --help``)
SKY_MODELS = {
    "preetham": "Preetham et al. 1999 analytic clear sky, spectral, with sun (needs --turbidity)",
    "preetham-overcast": "Preetham 1999 Sec. 5: Preetham sky blended into the CIE overcast sky at high turbidity",
    "cie": "CIE S 011/E:2003 standard general sky, 15 types (needs --sky-type)",
    "cie-overcast": "CIE overcast sky (Moon & Spencer 1942), luminance only",
    "cie-clear": "CIE 1973 clear sky (Kittler), luminance only",
    "perez": "Perez et al. 1993 all-weather sky (--epsilon/--delta or --dni/--dhi)",
    "hosek-wilkie": "Hosek & Wilkie 2012 spectral clear sky with the 2013 solar disc (--turbidity 1-10, --albedo)",
    "bruneton": "Bruneton & Neyret 2008 precomputed multiple scattering (any --altitude)",
}


def build_sky(name: str, sun_zenith: float, sun_azimuth: float, **options: Any) -> SkyModel:
    """Construct the sky model ``name`` for a sun position [rad]; ``options`` are the model's keyword arguments.

    Options that are None are dropped, so callers can pass every option they know.
    """
    opts = {k: v for k, v in options.items() if v is not None}
    if name == "preetham":
        from .preetham import PreethamSky

        return PreethamSky(opts.pop("turbidity", 2.5), sun_zenith, sun_azimuth, **opts)
    if name == "preetham-overcast":
        from .overcast_blend import PreethamOvercastBlendSky

        return PreethamOvercastBlendSky(opts.pop("turbidity", 8.0), sun_zenith, sun_azimuth, **opts)
    if name == "cie":
        from .cie import CIEStandardSky

        return CIEStandardSky(opts.pop("sky_type", 12), sun_zenith, sun_azimuth, **opts)
    if name == "cie-overcast":
        from .cie import CIEOvercastSky

        return CIEOvercastSky(**opts)
    if name == "cie-clear":
        from .cie import CIEClearSky

        return CIEClearSky(sun_zenith, sun_azimuth, **opts)
    if name == "perez":
        from .perez import PerezSky

        return PerezSky(sun_zenith, sun_azimuth, **opts)
    if name == "hosek-wilkie":
        from .hosek_wilkie import HosekWilkieSky

        return HosekWilkieSky(sun_zenith, sun_azimuth, **opts)
    if name == "bruneton":
        from ..precomputed.sky import BrunetonSky

        return BrunetonSky(sun_zenith, sun_azimuth, **opts)
    raise InvalidParameterError(f"unknown sky model {name!r}; choose one of {', '.join(SKY_MODELS)}")
