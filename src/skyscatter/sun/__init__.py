"""The sun: its position for a place and time, and its spectral radiance after the atmosphere."""

from .position import SunPosition, sun_position
from .sunlight import (
    SunTransmittances,
    extraterrestrial_radiance,
    sun_direct_normal_irradiance,
    sun_spectral_radiance,
    transmittances,
)

__all__ = [
    "SunPosition",
    "SunTransmittances",
    "extraterrestrial_radiance",
    "sun_direct_normal_irradiance",
    "sun_position",
    "sun_spectral_radiance",
    "transmittances",
]
