"""Sky models. One module per published model; all answer the protocol in :mod:`skyscatter.sky.base`.

The model classes are imported on first use (:mod:`skyscatter.lazy`), so ``from skyscatter.sky import
PreethamSky`` imports the Preetham model alone; :mod:`.registry` describes every model.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_namespace
from .base import SUN_ANGULAR_RADIUS, LuminanceOnlySky, SkyModel, SunSkyMixin, solar_disc_solid_angle

if TYPE_CHECKING:  # the names below, as type checkers see them (imported on first use at run time)
    from . import registry as registry
    from .asrc_cie import ASRCCIESky as ASRCCIESky
    from .bruneton import BrunetonSky as BrunetonSky
    from .cie import CIEClearSky as CIEClearSky
    from .cie import CIEOvercastSky as CIEOvercastSky
    from .cie import CIEStandardSky as CIEStandardSky
    from .hosek_wilkie import HosekWilkieSky as HosekWilkieSky
    from .montecarlo import MonteCarloSky as MonteCarloSky
    from .overcast_blend import PreethamOvercastBlendSky as PreethamOvercastBlendSky
    from .perez import PerezSky as PerezSky
    from .preetham import PreethamSky as PreethamSky

# public name -> submodule that defines it
_LAZY = {
    "ASRCCIESky": "asrc_cie",
    "BrunetonSky": "bruneton",
    "CIEClearSky": "cie",
    "CIEOvercastSky": "cie",
    "CIEStandardSky": "cie",
    "HosekWilkieSky": "hosek_wilkie",
    "MonteCarloSky": "montecarlo",
    "PreethamOvercastBlendSky": "overcast_blend",
    "PerezSky": "perez",
    "PreethamSky": "preetham",
}
_SUBMODULES = ("registry",)

__all__ = [
    "SUN_ANGULAR_RADIUS",
    "ASRCCIESky",
    "BrunetonSky",
    "CIEClearSky",
    "CIEOvercastSky",
    "CIEStandardSky",
    "HosekWilkieSky",
    "LuminanceOnlySky",
    "MonteCarloSky",
    "PerezSky",
    "PreethamOvercastBlendSky",
    "PreethamSky",
    "SkyModel",
    "SunSkyMixin",
    "registry",
    "solar_disc_solid_angle",
]

__getattr__, __dir__ = lazy_namespace(globals(), _LAZY, _SUBMODULES)
