"""The sun: its position for a place and time, and its spectral radiance after the atmosphere.

Names are imported on first use, so that code needing only the sun's position or disc (a sky matrix from an EPW
file) does not import the atmosphere behind the spectral sunlight.
"""

from __future__ import annotations

from ..lazy import lazy_namespace

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


__getattr__, __dir__ = lazy_namespace(globals(), _LAZY, _SUBMODULES)
