"""The sun: its position for a place and time, and its spectral radiance after the atmosphere.

Names are imported on first use, so that code needing only the sun's position or disc (a sky matrix from an EPW
file) does not import the atmosphere behind the spectral sunlight.
"""

from __future__ import annotations

import importlib
from typing import Any

# public name -> submodule that defines it
_LAZY = {
    "SUN_ANGULAR_RADIUS": "disc",
    "solar_disc_solid_angle": "disc",
    "SunPosition": "position",
    "sun_position": "position",
    "sun_position_unix": "position",
    "SunTransmittances": "sunlight",
    "extraterrestrial_radiance": "sunlight",
    "sun_direct_normal_irradiance": "sunlight",
    "sun_spectral_radiance": "sunlight",
    "transmittances": "sunlight",
}

_SUBMODULES = ("disc", "position", "spa", "sunlight")

__all__ = sorted(_LAZY)


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*__all__, *_SUBMODULES})
