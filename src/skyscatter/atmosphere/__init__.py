"""Clear-atmosphere optics: phase functions, Rayleigh and Mie (haze) scattering, optical mass, turbidity.

Every function takes wavelengths in nm and angles in radians and returns SI coefficients (m^-1, m^-1 sr^-1,
sr^-1). Functions of a scattering angle ``theta`` (shape (...)) and wavelengths (shape (n,)) return (..., n).
Formulas are those of Preetham, Shirley & Smits (1999), Appendix A.1 and A.3, unless stated otherwise.
"""

from .airmass import relative_optical_mass
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
from .phase import cornette_shanks, henyey_greenstein, rayleigh_phase
from .rayleigh import (
    AIR_NUMBER_DENSITY,
    AIR_REFRACTIVE_INDEX,
    DEPOLARISATION,
    king_factor,
    rayleigh_angular_scattering,
    rayleigh_total_scattering,
)
from .turbidity import (
    ANGSTROM_ALPHA,
    KOSCHMIEDER_CONSTANT,
    angstrom_beta,
    meteorological_range,
    turbidity_from_meteorological_range,
)

__all__ = [
    "AIR_NUMBER_DENSITY",
    "AIR_REFRACTIVE_INDEX",
    "ANGSTROM_ALPHA",
    "DEPOLARISATION",
    "JUNGE_EXPONENT",
    "KOSCHMIEDER_CONSTANT",
    "angstrom_beta",
    "cornette_shanks",
    "eta_integral_ratio",
    "haze_concentration",
    "henyey_greenstein",
    "king_factor",
    "meteorological_range",
    "mie_angular_scattering",
    "mie_eta",
    "mie_k",
    "mie_phase_function",
    "mie_total_scattering",
    "rayleigh_angular_scattering",
    "rayleigh_phase",
    "rayleigh_total_scattering",
    "relative_optical_mass",
    "turbidity_from_meteorological_range",
]
