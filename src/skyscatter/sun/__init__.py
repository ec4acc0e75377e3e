"""The sun: its position for a place and time, and its spectral radiance after the atmosphere."""

from .disc import SUN_ANGULAR_RADIUS, solar_disc_solid_angle
from .position import SunPosition, sun_position
from .sunlight import (
    SunTransmittances,
    extraterrestrial_radiance,
    sun_direct_normal_irradiance,
    sun_spectral_radiance,
    transmittances,
)

__all__ = [
    "SUN_ANGULAR_RADIUS",
    "SunPosition",
    "SunTransmittances",
    "extraterrestrial_radiance",
    "sun_direct_normal_irradiance",
    "sun_position",
    "solar_disc_solid_angle",
    "sun_spectral_radiance",
    "transmittances",
]
