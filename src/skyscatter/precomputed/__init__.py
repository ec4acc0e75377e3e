"""Precomputed atmospheric scattering (Bruneton & Neyret 2008): multiple scattering from the ground to space.

* :class:`AtmosphereParameters` - the atmosphere (Earth defaults).
* :class:`PrecomputedAtmosphere` - tables from :meth:`~PrecomputedAtmosphere.compute` (Algorithm 4.1) and
  the rendering functions (sky radiance, aerial perspective, light shafts, irradiance, sun).
* :func:`cached_atmosphere` - the same, cached on disk keyed by a hash of everything that affects the tables.
* :func:`resolve_atmosphere` - tables for an argument that is tables, parameters or None.

The sky model built on the tables is :class:`skyscatter.sky.bruneton.BrunetonSky` (also ``skyscatter.BrunetonSky``);
the aerial perspective from the tables is in :mod:`skyscatter.aerial.bruneton`, camera views and the landscape
with light shafts in :mod:`skyscatter.render.bruneton`.
"""

from ..lazy import lazy_namespace
from .cache import CacheRebuildWarning, cache_dir, cached_atmosphere, resolve_atmosphere
from .parameters import (
    AtmosphereParameters,
    DensityLayer,
    DensityProfile,
    PowerLawSpectrum,
    Spectrum,
    TabulatedSpectrum,
    rayleigh_scattering_physical,
)
from .tables import DEFAULT_ORDERS, DEFAULT_TABLE_WAVELENGTHS, PrecomputedAtmosphere, TableSizes

__all__ = [
    "DEFAULT_ORDERS",
    "DEFAULT_TABLE_WAVELENGTHS",
    "AtmosphereParameters",
    "BrunetonSky",
    "CacheRebuildWarning",
    "DensityLayer",
    "DensityProfile",
    "PowerLawSpectrum",
    "PrecomputedAtmosphere",
    "Spectrum",
    "TableSizes",
    "TabulatedSpectrum",
    "cache_dir",
    "cached_atmosphere",
    "rayleigh_scattering_physical",
    "resolve_atmosphere",
]

# Backwards-compatibility alias: BrunetonSky moved to skyscatter.sky.bruneton (one module per sky model in
# skyscatter.sky); ``from skyscatter.precomputed import BrunetonSky`` keeps working. Imported on first use because
# the sky layer sits above this one (skyscatter.sky.bruneton imports this package); for the same reason type
# checkers see it as Any here (the documented name is skyscatter.sky.BrunetonSky).
__getattr__ = lazy_namespace(globals(), {"BrunetonSky": ".sky.bruneton"})[0]
