"""skyscatter: physically based daylight.

Sun position, spectral sunlight, sky models (Preetham 1999, CIE, Perez 1993, ASRC-CIE, Hosek & Wilkie 2012,
Bruneton & Neyret 2008), fitting of the Hosek-Wilkie form to any atmosphere, aerial perspective and sky/landscape
images.
Frame, units and colour conventions are in ``docs/conventions.md``: ENU directions, radians, nm, SI radiometric
units, cd m^-2.

Public names are imported lazily so ``import skyscatter`` stays fast.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

__version__ = "0.1.0"

# Before any compiled kernel is defined: a read-only install with an unwritable HOME still gets a numba cache.
from .fileio import ensure_numba_cache as _ensure_numba_cache  # noqa: E402

_ensure_numba_cache(__path__[0])

from .lazy import lazy_namespace  # noqa: E402

if TYPE_CHECKING:  # the names below, as type checkers see them (imported on first use at run time)
    from . import aerial as aerial
    from . import atmosphere as atmosphere
    from . import conventions as conventions
    from . import epw as epw
    from . import errors as errors
    from . import fit as fit
    from . import patches as patches
    from . import photometry as photometry
    from . import precomputed as precomputed
    from . import realtime as realtime
    from . import render as render
    from . import sky as sky
    from . import spectral as spectral
    from . import sun as sun
    from .sky.asrc_cie import ASRCCIESky as ASRCCIESky
    from .sky.bruneton import BrunetonSky as BrunetonSky
    from .sky.cie import CIEClearSky as CIEClearSky
    from .sky.cie import CIEOvercastSky as CIEOvercastSky
    from .sky.cie import CIEStandardSky as CIEStandardSky
    from .sky.hosek_wilkie import HosekWilkieSky as HosekWilkieSky
    from .sky.perez import PerezSky as PerezSky
    from .sky.preetham import PreethamSky as PreethamSky
    from .sky_matrix import skymatrix as skymatrix
    from .sun.position import sun_position as sun_position

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
