"""skyscatter: physically based daylight.

Sun position, spectral sunlight, sky models (Preetham 1999, CIE, Perez 1993, Hosek & Wilkie 2012, Bruneton &
Neyret 2008), fitting of the Hosek-Wilkie form to any atmosphere, aerial perspective and sky/landscape images.
Frame, units and colour conventions are in ``docs/conventions.md``: ENU directions, radians, nm, SI radiometric
units, cd m^-2.

Public names are imported lazily so ``import skyscatter`` stays fast.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

# Before any compiled kernel is defined: a read-only install with an unwritable HOME still gets a numba cache.
from .fileio import ensure_numba_cache as _ensure_numba_cache  # noqa: E402

_ensure_numba_cache(__path__[0])

# public name -> module that defines it
_LAZY = {
    "sun_position": "skyscatter.sun.position",
    "PreethamSky": "skyscatter.sky.preetham",
    "CIEOvercastSky": "skyscatter.sky.cie",
    "CIEClearSky": "skyscatter.sky.cie",
    "CIEStandardSky": "skyscatter.sky.cie",
    "PerezSky": "skyscatter.sky.perez",
    "HosekWilkieSky": "skyscatter.sky.hosek_wilkie",
    "skymatrix": "skyscatter.sky_matrix",
    "BrunetonSky": "skyscatter.sky.bruneton",
}
_SUBMODULES = {
    "aerial",
    "atmosphere",
    "conventions",
    "epw",
    "errors",
    "fit",
    "patches",
    "photometry",
    "precomputed",
    "render",
    "sky",
    "spectral",
    "sun",
}

__all__ = sorted([*_LAZY, *_SUBMODULES, "__version__"])


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    if name in _SUBMODULES:
        return importlib.import_module(f"skyscatter.{name}")
    raise AttributeError(f"module 'skyscatter' has no attribute {name!r}")


def __dir__() -> list[str]:
    return __all__
