"""The medium: clear-atmosphere optics and the one description of the atmosphere for every model.

* :mod:`.medium` - :class:`AtmosphereParameters` (planet, density profiles, Rayleigh/aerosol/ozone
  coefficients, aerosol phase function, ground albedo, solar spectrum), with the per-altitude coefficients and
  phase-function sampling a path tracer needs; :class:`DensityProfile`.
* :mod:`.particles` - particle components (aerosols, cloud droplets): density profile, extinction and albedo
  spectra and a phase table each; :mod:`.phase_table` - tabulated per-wavelength phase functions
  (:class:`PhaseTable`: evaluation, inverse-CDF sampling, Legendre moments, delta-M; numba versions);
  :mod:`.profiles` - density profiles.
* :mod:`.spectra` - spectral inputs (power law, table, physical Rayleigh) and the published data they use.
* :mod:`.phase` - Rayleigh, Henyey-Greenstein and Cornette-Shanks phase functions and their samplers.
* :mod:`.rayleigh` - the Rayleigh formula with one set of physical constants ([Bodhaine1999])
  and the A.3 constants of [Preetham1999].
* :mod:`.mie`, :mod:`.turbidity`, :mod:`.airmass` - [Preetham1999] Appendix A.1 and A.3 (haze, Angstrom
  turbidity, optical mass).
* :mod:`.tables` - the one loader of the packaged data tables.

Every function takes wavelengths in nm and angles in radians and returns SI coefficients (m^-1, m^-1 sr^-1,
sr^-1). Functions of a scattering angle ``theta`` (shape (...)) and wavelengths (shape (n,)) return (..., n).
Importing this package imports neither numba nor colour-science, and its names are imported on first use
(``import skyscatter.atmosphere.airmass`` alone stays quick).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy import lazy_namespace

if TYPE_CHECKING:  # the names below, as type checkers see them (imported on first use at run time)
    from . import airmass as airmass
    from . import medium as medium
    from . import mie as mie
    from . import particles as particles
    from . import phase as phase
    from . import phase_table as phase_table
    from . import profiles as profiles
    from . import rayleigh as rayleigh
    from . import spectra as spectra
    from . import tables as tables
    from . import turbidity as turbidity
    from .airmass import relative_optical_mass as relative_optical_mass
    from .airmass import relative_optical_mass_kasten1966 as relative_optical_mass_kasten1966
    from .medium import AtmosphereParameters as AtmosphereParameters
    from .mie import JUNGE_EXPONENT as JUNGE_EXPONENT
    from .mie import eta_integral_ratio as eta_integral_ratio
    from .mie import haze_concentration as haze_concentration
    from .mie import mie_angular_scattering as mie_angular_scattering
    from .mie import mie_eta as mie_eta
    from .mie import mie_k as mie_k
    from .mie import mie_phase_function as mie_phase_function
    from .mie import mie_total_scattering as mie_total_scattering
    from .particles import AnalyticParticles as AnalyticParticles
    from .particles import ParticleComponent as ParticleComponent
    from .particles import TabulatedParticles as TabulatedParticles
    from .phase import AEROSOL_PHASE_FUNCTIONS as AEROSOL_PHASE_FUNCTIONS
    from .phase import aerosol_phase as aerosol_phase
    from .phase import cornette_shanks as cornette_shanks
    from .phase import henyey_greenstein as henyey_greenstein
    from .phase import henyey_greenstein_inverse_cdf as henyey_greenstein_inverse_cdf
    from .phase import rayleigh_inverse_cdf as rayleigh_inverse_cdf
    from .phase import rayleigh_phase as rayleigh_phase
    from .phase import sample_aerosol_phase as sample_aerosol_phase
    from .phase import sample_cornette_shanks as sample_cornette_shanks
    from .phase import sample_henyey_greenstein as sample_henyey_greenstein
    from .phase import sample_rayleigh as sample_rayleigh
    from .phase_table import PhaseTable as PhaseTable
    from .phase_table import phase_angle_grid as phase_angle_grid
    from .profiles import DensityLayer as DensityLayer
    from .profiles import DensityProfile as DensityProfile
    from .rayleigh import AIR_NUMBER_DENSITY as AIR_NUMBER_DENSITY
    from .rayleigh import AIR_NUMBER_DENSITY_PREETHAM1999 as AIR_NUMBER_DENSITY_PREETHAM1999
    from .rayleigh import AIR_REFRACTIVE_INDEX as AIR_REFRACTIVE_INDEX
    from .rayleigh import AIR_REFRACTIVE_INDEX_PREETHAM1999 as AIR_REFRACTIVE_INDEX_PREETHAM1999
    from .rayleigh import DEPOLARISATION as DEPOLARISATION
    from .rayleigh import STANDARD_AIR_NUMBER_DENSITY as STANDARD_AIR_NUMBER_DENSITY
    from .rayleigh import king_factor as king_factor
    from .rayleigh import rayleigh_angular_scattering as rayleigh_angular_scattering
    from .rayleigh import rayleigh_angular_scattering_preetham1999 as rayleigh_angular_scattering_preetham1999
    from .rayleigh import rayleigh_scattering_bodhaine1999 as rayleigh_scattering_bodhaine1999
    from .rayleigh import rayleigh_total_scattering as rayleigh_total_scattering
    from .rayleigh import rayleigh_total_scattering_preetham1999 as rayleigh_total_scattering_preetham1999
    from .rayleigh import refractive_index_standard_air as refractive_index_standard_air
    from .spectra import DOBSON_UNIT as DOBSON_UNIT
    from .spectra import AngstromSpectrum as AngstromSpectrum
    from .spectra import PowerLawSpectrum as PowerLawSpectrum
    from .spectra import RayleighPhysicalSpectrum as RayleighPhysicalSpectrum
    from .spectra import Spectrum as Spectrum
    from .spectra import TabulatedSpectrum as TabulatedSpectrum
    from .spectra import ozone_cross_section_serdyuchenko as ozone_cross_section_serdyuchenko
    from .spectra import rayleigh_scattering_physical as rayleigh_scattering_physical
    from .spectra import solar_spectrum_astm_g173 as solar_spectrum_astm_g173
    from .turbidity import ANGSTROM_ALPHA as ANGSTROM_ALPHA
    from .turbidity import KOSCHMIEDER_CONSTANT as KOSCHMIEDER_CONSTANT
    from .turbidity import angstrom_beta as angstrom_beta
    from .turbidity import meteorological_range as meteorological_range
    from .turbidity import turbidity_from_meteorological_range as turbidity_from_meteorological_range

# public name -> submodule that defines it
_LAZY = {
    "AEROSOL_PHASE_FUNCTIONS": "phase",
    "AIR_NUMBER_DENSITY": "rayleigh",
    "AIR_NUMBER_DENSITY_PREETHAM1999": "rayleigh",
    "AIR_REFRACTIVE_INDEX": "rayleigh",
    "AIR_REFRACTIVE_INDEX_PREETHAM1999": "rayleigh",
    "ANGSTROM_ALPHA": "turbidity",
    "DEPOLARISATION": "rayleigh",
    "DOBSON_UNIT": "spectra",
    "JUNGE_EXPONENT": "mie",
    "KOSCHMIEDER_CONSTANT": "turbidity",
    "STANDARD_AIR_NUMBER_DENSITY": "rayleigh",
    "AnalyticParticles": "particles",
    "AngstromSpectrum": "spectra",
    "AtmosphereParameters": "medium",
    "DensityLayer": "profiles",
    "DensityProfile": "profiles",
    "ParticleComponent": "particles",
    "PhaseTable": "phase_table",
    "TabulatedParticles": "particles",
    "PowerLawSpectrum": "spectra",
    "RayleighPhysicalSpectrum": "spectra",
    "Spectrum": "spectra",
    "TabulatedSpectrum": "spectra",
    "aerosol_phase": "phase",
    "angstrom_beta": "turbidity",
    "cornette_shanks": "phase",
    "eta_integral_ratio": "mie",
    "haze_concentration": "mie",
    "henyey_greenstein": "phase",
    "henyey_greenstein_inverse_cdf": "phase",
    "king_factor": "rayleigh",
    "meteorological_range": "turbidity",
    "mie_angular_scattering": "mie",
    "mie_eta": "mie",
    "mie_k": "mie",
    "mie_phase_function": "mie",
    "mie_total_scattering": "mie",
    "phase_angle_grid": "phase_table",
    "ozone_cross_section_serdyuchenko": "spectra",
    "rayleigh_angular_scattering": "rayleigh",
    "rayleigh_angular_scattering_preetham1999": "rayleigh",
    "rayleigh_inverse_cdf": "phase",
    "rayleigh_phase": "phase",
    "rayleigh_scattering_bodhaine1999": "rayleigh",
    "rayleigh_scattering_physical": "spectra",
    "rayleigh_total_scattering": "rayleigh",
    "rayleigh_total_scattering_preetham1999": "rayleigh",
    "refractive_index_standard_air": "rayleigh",
    "relative_optical_mass": "airmass",
    "relative_optical_mass_kasten1966": "airmass",
    "sample_aerosol_phase": "phase",
    "sample_cornette_shanks": "phase",
    "sample_henyey_greenstein": "phase",
    "sample_rayleigh": "phase",
    "solar_spectrum_astm_g173": "spectra",
    "turbidity_from_meteorological_range": "turbidity",
}
_SUBMODULES = ("airmass", "medium", "mie", "particles", "phase", "phase_table", "profiles", "rayleigh", "spectra",
               "tables", "turbidity")

__all__ = sorted(_LAZY)


__getattr__, __dir__ = lazy_namespace(globals(), _LAZY, _SUBMODULES)
