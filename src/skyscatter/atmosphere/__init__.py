"""The medium: clear-atmosphere optics and the one description of the atmosphere for every model.

* :mod:`.medium` - :class:`AtmosphereParameters` (planet, density profiles, Rayleigh/aerosol/ozone
  coefficients, aerosol phase function, ground albedo, solar spectrum), with the per-altitude coefficients and
  phase-function sampling a path tracer needs; :class:`DensityProfile`.
* :mod:`.spectra` - spectral inputs (power law, table, physical Rayleigh) and the published data they use.
* :mod:`.phase` - Rayleigh, Henyey-Greenstein and Cornette-Shanks phase functions and their samplers.
* :mod:`.rayleigh` - the Rayleigh formula with one set of physical constants (Bodhaine et al. 1999,
  doi:10.1175/1520-0426(1999)016<1854:ORODC>2.0.CO;2) and Preetham's (1999) A.3 constants.
* :mod:`.mie`, :mod:`.turbidity`, :mod:`.airmass` - Preetham, Shirley & Smits (1999), "A Practical Analytic
  Model for Daylight", doi:10.1145/311535.311545, Appendix A.1 and A.3 (haze, Angstrom turbidity, optical mass).
* :mod:`.tables` - the one loader of the packaged data tables.

Every function takes wavelengths in nm and angles in radians and returns SI coefficients (m^-1, m^-1 sr^-1,
sr^-1). Functions of a scattering angle ``theta`` (shape (...)) and wavelengths (shape (n,)) return (..., n).
Importing this package imports neither numba nor colour-science.
"""

from .airmass import relative_optical_mass, relative_optical_mass_kasten1966
from .medium import AtmosphereParameters, DensityLayer, DensityProfile
from .mie import (
    JUNGE_EXPONENT,
    eta_integral_ratio,
    haze_concentration,
    mie_angular_scattering,
    mie_eta,
    mie_k,
    mie_phase_function,
    mie_total_scattering,
)
from .phase import (
    AEROSOL_PHASE_FUNCTIONS,
    aerosol_phase,
    cornette_shanks,
    henyey_greenstein,
    henyey_greenstein_inverse_cdf,
    rayleigh_inverse_cdf,
    rayleigh_phase,
    sample_aerosol_phase,
    sample_cornette_shanks,
    sample_henyey_greenstein,
    sample_rayleigh,
)
from .rayleigh import (
    AIR_NUMBER_DENSITY,
    AIR_NUMBER_DENSITY_PREETHAM1999,
    AIR_REFRACTIVE_INDEX,
    AIR_REFRACTIVE_INDEX_PREETHAM1999,
    DEPOLARISATION,
    STANDARD_AIR_NUMBER_DENSITY,
    king_factor,
    rayleigh_angular_scattering,
    rayleigh_angular_scattering_preetham1999,
    rayleigh_scattering_bodhaine1999,
    rayleigh_total_scattering,
    rayleigh_total_scattering_preetham1999,
    refractive_index_standard_air,
)
from .spectra import (
    DOBSON_UNIT,
    PowerLawSpectrum,
    RayleighPhysicalSpectrum,
    Spectrum,
    TabulatedSpectrum,
    ozone_cross_section_serdyuchenko,
    rayleigh_scattering_physical,
    solar_spectrum_astm_g173,
)
from .turbidity import (
    ANGSTROM_ALPHA,
    KOSCHMIEDER_CONSTANT,
    angstrom_beta,
    meteorological_range,
    turbidity_from_meteorological_range,
)

__all__ = [
    "AEROSOL_PHASE_FUNCTIONS",
    "AIR_NUMBER_DENSITY",
    "AIR_NUMBER_DENSITY_PREETHAM1999",
    "AIR_REFRACTIVE_INDEX",
    "AIR_REFRACTIVE_INDEX_PREETHAM1999",
    "ANGSTROM_ALPHA",
    "DEPOLARISATION",
    "DOBSON_UNIT",
    "JUNGE_EXPONENT",
    "KOSCHMIEDER_CONSTANT",
    "STANDARD_AIR_NUMBER_DENSITY",
    "AtmosphereParameters",
    "DensityLayer",
    "DensityProfile",
    "PowerLawSpectrum",
    "RayleighPhysicalSpectrum",
    "Spectrum",
    "TabulatedSpectrum",
    "aerosol_phase",
    "angstrom_beta",
    "cornette_shanks",
    "eta_integral_ratio",
    "haze_concentration",
    "henyey_greenstein",
    "henyey_greenstein_inverse_cdf",
    "king_factor",
    "meteorological_range",
    "mie_angular_scattering",
    "mie_eta",
    "mie_k",
    "mie_phase_function",
    "mie_total_scattering",
    "ozone_cross_section_serdyuchenko",
    "rayleigh_angular_scattering",
    "rayleigh_angular_scattering_preetham1999",
    "rayleigh_inverse_cdf",
    "rayleigh_phase",
    "rayleigh_scattering_bodhaine1999",
    "rayleigh_scattering_physical",
    "rayleigh_total_scattering",
    "rayleigh_total_scattering_preetham1999",
    "refractive_index_standard_air",
    "relative_optical_mass",
    "relative_optical_mass_kasten1966",
    "sample_aerosol_phase",
    "sample_cornette_shanks",
    "sample_henyey_greenstein",
    "sample_rayleigh",
    "solar_spectrum_astm_g173",
    "turbidity_from_meteorological_range",
]
