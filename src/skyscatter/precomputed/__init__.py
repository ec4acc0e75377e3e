"""Precomputed atmospheric scattering (Bruneton & Neyret 2008): multiple scattering from the ground to space.

* :class:`AtmosphereParameters` - the atmosphere (Earth defaults).
* :class:`PrecomputedAtmosphere` - tables from :meth:`~PrecomputedAtmosphere.compute` (Algorithm 4.1) and
  the rendering functions (sky radiance, aerial perspective, light shafts, irradiance, sun).
* :func:`cached_atmosphere` - the same, cached on disk keyed by a hash of everything that affects the tables.
* :class:`skyscatter.BrunetonSky` (in :mod:`.sky`) - the sky protocol for an observer at any altitude.
"""

from .cache import CacheRebuildWarning, cache_dir, cached_atmosphere
from .parameters import (
    AtmosphereParameters,
    DensityLayer,
    DensityProfile,
    PowerLawSpectrum,
    Spectrum,
    TabulatedSpectrum,
    rayleigh_scattering_physical,
)
from .sky import BrunetonSky
from .tables import DEFAULT_TABLE_WAVELENGTHS, PrecomputedAtmosphere, TableSizes

__all__ = [
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
]
