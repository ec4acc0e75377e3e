"""The atmosphere of the precomputed model: re-exports of :mod:`skyscatter.atmosphere` (same objects).

The medium (:class:`AtmosphereParameters`, density profiles, spectra and data loaders) is described once in
:mod:`skyscatter.atmosphere.medium` and :mod:`skyscatter.atmosphere.spectra`; this module keeps the former
import paths (``skyscatter.precomputed.parameters.X``) working.
"""

from ..atmosphere.medium import SOLAR_BAND_WIDTH, AtmosphereParameters, DensityLayer, DensityProfile
from ..atmosphere.spectra import (
    DOBSON_UNIT,
    PowerLawSpectrum,
    RayleighPhysicalSpectrum,
    Spectrum,
    TabulatedSpectrum,
    ozone_cross_section_serdyuchenko,
    rayleigh_scattering_physical,
    solar_spectrum_astm_g173,
)

__all__ = [
    "DOBSON_UNIT",
    "SOLAR_BAND_WIDTH",
    "AtmosphereParameters",
    "DensityLayer",
    "DensityProfile",
    "PowerLawSpectrum",
    "RayleighPhysicalSpectrum",
    "Spectrum",
    "TabulatedSpectrum",
    "ozone_cross_section_serdyuchenko",
    "rayleigh_scattering_physical",
    "solar_spectrum_astm_g173",
]
