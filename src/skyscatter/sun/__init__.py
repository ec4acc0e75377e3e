"""The sun: its position for a place and time, and its spectral radiance after the atmosphere.

Names are imported on first use, so that code needing only the sun's position or disc (a sky matrix from an EPW
file) does not import the atmosphere behind the spectral sunlight.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_namespace

if TYPE_CHECKING:  # the names below, as type checkers see them (imported on first use at run time)
    from . import disc as disc
    from . import position as position
    from . import spa as spa
    from . import sunlight as sunlight
    from .disc import SUN_ANGULAR_RADIUS as SUN_ANGULAR_RADIUS
    from .disc import solar_disc_solid_angle as solar_disc_solid_angle
    from .position import SunPosition as SunPosition
    from .position import sun_position as sun_position
    from .position import sun_position_unix as sun_position_unix
    from .sunlight import SunTransmittances as SunTransmittances
    from .sunlight import extraterrestrial_radiance as extraterrestrial_radiance
    from .sunlight import sun_direct_normal_irradiance as sun_direct_normal_irradiance
    from .sunlight import sun_spectral_radiance as sun_spectral_radiance
    from .sunlight import transmittances as transmittances

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
