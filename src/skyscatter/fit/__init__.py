"""Fitting analytic sky forms to any sky model skyscatter can compute.

:func:`fit_hosek_wilkie` fits the Hosek & Wilkie 2012 form ([HosekWilkie2012]) to a
callable that builds sky models for sun positions, and returns a :class:`HosekWilkieDataset` that
:class:`skyscatter.HosekWilkieSky` evaluates (``HosekWilkieSky(sun_zenith, sun_azimuth, dataset=ds)``).
"""

from __future__ import annotations

from ..sky.hosek_wilkie import HosekWilkieDataset
from .hosek_wilkie import default_sample_directions, fit_hosek_wilkie, fit_sun_elevations, sky_fit_error

__all__ = [
    "HosekWilkieDataset",
    "default_sample_directions",
    "fit_hosek_wilkie",
    "fit_sun_elevations",
    "sky_fit_error",
]
