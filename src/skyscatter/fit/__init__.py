"""Fitting analytic sky forms to any sky model skyscatter can compute.

:func:`fit_hosek_wilkie` fits the Hosek & Wilkie 2012 form ([HosekWilkie2012]) to a
callable that builds sky models for sun positions, and returns a :class:`HosekWilkieDataset` that
:class:`skyscatter.HosekWilkieSky` evaluates (``HosekWilkieSky(sun_zenith, sun_azimuth, dataset=ds)``).
:func:`fit_atmosphere` retrieves the air (aerosol, ground albedo) from a sky scan, DNI/DHI or optical depths
(:mod:`.atmosphere`).
"""

from __future__ import annotations

from ..sky.hosek_wilkie import HosekWilkieDataset
from .atmosphere import AerosolOpticalDepth, AtmosphereFit, Irradiance, SkyScan, fit_atmosphere
from .hosek_wilkie import default_sample_directions, fit_hosek_wilkie, fit_sun_elevations, sky_fit_error

__all__ = [
    "AerosolOpticalDepth",
    "AtmosphereFit",
    "HosekWilkieDataset",
    "Irradiance",
    "SkyScan",
    "fit_atmosphere",
    "default_sample_directions",
    "fit_hosek_wilkie",
    "fit_sun_elevations",
    "sky_fit_error",
]
