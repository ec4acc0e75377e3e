"""Sky models. One module per published model; all answer the protocol in :mod:`skyscatter.sky.base`."""

from .base import SUN_ANGULAR_RADIUS, LuminanceOnlySky, SkyModel, SunSkyMixin, solar_disc_solid_angle

__all__ = ["SUN_ANGULAR_RADIUS", "LuminanceOnlySky", "SkyModel", "SunSkyMixin", "solar_disc_solid_angle"]
