"""skyscatter: physically based daylight.

Sun position, spectral sunlight, sky models (Preetham 1999, CIE, Perez 1993, ASRC-CIE, Hosek & Wilkie 2012,
Bruneton & Neyret 2008), fitting of the Hosek-Wilkie form to any atmosphere, aerial perspective and sky/landscape
images.
Frame, units and colour conventions are in ``docs/conventions.md``: ENU directions, radians, nm, SI radiometric
units, cd m^-2.

Public names are imported lazily so ``import skyscatter`` stays fast.
"""

from __future__ import annotations

__version__ = "0.1.0"

# Before any compiled kernel is defined: a read-only install with an unwritable HOME still gets a numba cache.
from .fileio import ensure_numba_cache as _ensure_numba_cache  # noqa: E402

_ensure_numba_cache(__path__[0])

from .lazy import lazy_namespace  # noqa: E402

# public name -> module that defines it
_LAZY = {
    "sun_position": "sun.position",
    "PreethamSky": "sky.preetham",
    "CIEOvercastSky": "sky.cie",
    "CIEClearSky": "sky.cie",
    "CIEStandardSky": "sky.cie",
    "PerezSky": "sky.perez",
    "ASRCCIESky": "sky.asrc_cie",
    "HosekWilkieSky": "sky.hosek_wilkie",
    "skymatrix": "sky_matrix",
    "BrunetonSky": "sky.bruneton",
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
    "realtime",
    "render",
    "sky",
    "spectral",
    "sun",
}

__all__ = sorted([*_LAZY, *_SUBMODULES, "__version__"])


__getattr__, __dir__ = lazy_namespace(globals(), _LAZY, _SUBMODULES)
