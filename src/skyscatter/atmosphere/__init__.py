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

from ..lazy import lazy_namespace

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
