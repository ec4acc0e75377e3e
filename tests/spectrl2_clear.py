"""Our clear sky against pvlib's SPECTRL2 through SPECTRL2's own aerosol (Bird & Riordan 1986): the medium and the
ground spectra both sides, shared by tests/test_spectral_skymatrix.py and benchmarks/compare_spectrl2_own_aerosol.py
(docs/sky_matrices.md, "Clear hours against SPECTRL2 through SPECTRL2's own aerosol")."""

from __future__ import annotations

import numpy as np
import pvlib

#: Angstrom exponent of the SPECTRL2 comparison (both models; pvlib's default is 1.14).
SPECTRL2_ALPHA = 1.3


def spectrl2_air(aod550: float, phase=None):
    """Our medium (the retrieval's base: physical Rayleigh, ozone 300 DU, ground albedo 0.2) with SPECTRL2's own
    aerosol (Bird & Riordan 1986): vertical optical depth ``aod550 (lambda / 550 nm)^-1.3`` (Eq. 2-7, Angstrom's
    law) over the base's aerosol profile, single-scattering albedo ``0.945 exp(-0.095 ln^2(lambda / 400 nm))``
    (Eq. 3-16) and the asymmetry factor 0.65 of Eqs. 3-11 to 3-14 as a Henyey-Greenstein phase (its mean cosine
    is its g; SPECTRL2's forward-scattering fraction Fs is that of this phase within 0.9 % at sun zeniths 0-78 deg),
    given as a tabulated particle component. ``phase``: another :class:`PhaseTable` instead (e.g. a
    Cornette-Shanks of the same mean cosine)."""
    from skyscatter.atmosphere.particles import TabulatedParticles
    from skyscatter.atmosphere.phase_table import PhaseTable
    from skyscatter.atmosphere.spectra import AngstromSpectrum, TabulatedSpectrum
    from skyscatter.fit.weather import RetrievalOptions

    base = RetrievalOptions(angstrom_alpha=SPECTRL2_ALPHA).base_atmosphere()
    wl = np.arange(300.0, 1301.0, 10.0)
    albedo = 0.945 * np.exp(-0.095 * np.log(wl / 400.0) ** 2)
    column = base.mie_density.column(base.thickness)
    aerosol = TabulatedParticles(
        "SPECTRL2 aerosol", base.mie_density,
        AngstromSpectrum(aod550 * 0.55**SPECTRL2_ALPHA, SPECTRL2_ALPHA, column, "SPECTRL2 aerosol extinction"),
        TabulatedSpectrum(tuple(wl), tuple(albedo), "SPECTRL2 aerosol albedo"),
        PhaseTable.henyey_greenstein(0.65, [300.0, 1300.0]) if phase is None else phase)
    return base.replace(aerosol=aerosol)


def clear_ground_spectra(atm, tables, zenith_deg: float, aod550: float):
    """Horizontal direct, diffuse and global transmittances (irradiance over the extraterrestrial normal
    irradiance, each model over its own, mean Sun-Earth distance) of our clear sky and of pvlib's SPECTRL2 at
    SPECTRL2's wavelengths in 400-700 nm: ``(wavelengths [nm], ours, theirs, diffuse_gas)``, the two as dicts of
    arrays; ours: the broadband model's direct beam and the tables' radiance over the hemisphere
    (``horizontal_sky_irradiance``, what the matrix closes on) times the water and mixed-gas transmittance along
    the sun's path (``diffuse_gas``); water 1.4 cm, ozone 300 DU, sea level, ground albedo 0.2, day 80."""
    import importlib

    from skyscatter.fit.weather import BroadbandClearSky

    model = BroadbandClearSky(atm, SPECTRL2_ALPHA)
    z = np.radians([zenith_deg])
    one = np.ones(1)
    direct = model.direct_normal_spectral(z, [aod550], 1.4 * one, 101325 * one, 300 * one, one,
                                          weighted=False)[0] / model.e0
    gas = model.gas_transmittance(z, 1.4 * one, 101325 * one)[0]
    wlt = np.asarray(tables.wavelengths)
    sky = tables.horizontal_sky_irradiance(z)[0] / atm.solar_irradiance_at(wlt)
    s = pvlib.spectrum.spectrl2(apparent_zenith=zenith_deg, aoi=zenith_deg, surface_tilt=0, ground_albedo=0.2,
                                surface_pressure=101325,
                                relative_airmass=pvlib.atmosphere.get_relative_airmass(zenith_deg, model="kasten1966"),
                                precipitable_water=1.4, ozone=0.3, dayofyear=80, alpha=SPECTRL2_ALPHA,
                                aerosol_turbidity_500nm=aod550 * (500 / 550) ** -SPECTRL2_ALPHA)
    etr = importlib.import_module("pvlib.spectrum.spectrl2")._SPECTRL2_COEFFS["spectral_irradiance_et"]
    e0 = etr * pvlib.irradiance.get_extra_radiation(80, method="spencer", solar_constant=1.0)
    w = s["wavelength"]
    sel = (w >= 400) & (w <= 700)
    w = w[sel]
    cz = np.cos(z[0])
    theirs = {"direct": s["dni"][sel, 0] / e0[sel] * cz, "diffuse": s["dhi"][sel, 0] / e0[sel]}
    gas_w = np.interp(w, model.wavelengths, gas)
    ours = {"direct": np.interp(w, model.wavelengths, direct) * cz, "diffuse": np.interp(w, wlt, sky) * gas_w}
    for d in (theirs, ours):
        d["global"] = d["direct"] + d["diffuse"]
    return w, ours, theirs, gas_w
