"""The medium in skyscatter.atmosphere: one set of constants, the phase functions and their sampling, the
per-altitude coefficients a path tracer needs, and the re-exports kept for skyscatter.precomputed."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from scipy import integrate, stats

import skyscatter.atmosphere as atmosphere
from skyscatter.atmosphere import (
    AIR_NUMBER_DENSITY_PREETHAM1999,
    AIR_REFRACTIVE_INDEX_PREETHAM1999,
    DOBSON_UNIT,
    STANDARD_AIR_NUMBER_DENSITY,
    AtmosphereParameters,
    angstrom_beta,
    cornette_shanks,
    henyey_greenstein,
    henyey_greenstein_inverse_cdf,
    king_factor,
    rayleigh_inverse_cdf,
    rayleigh_phase,
    rayleigh_scattering_bodhaine1999,
    rayleigh_scattering_physical,
    rayleigh_total_scattering_preetham1999,
    refractive_index_standard_air,
    sample_cornette_shanks,
    sample_henyey_greenstein,
    sample_rayleigh,
)
from skyscatter.atmosphere import phase as phase_module
from skyscatter.errors import FileFormatError, InvalidParameterError

WL = np.array([400.0, 450.0, 550.0, 650.0, 700.0])
N_SAMPLES = 20000


# ------------------------------------------------------------------ one object, cheap import


def test_precomputed_reexports_are_the_same_objects():
    import skyscatter.precomputed as pre
    import skyscatter.precomputed.parameters as pp

    assert pre.AtmosphereParameters is atmosphere.AtmosphereParameters is pp.AtmosphereParameters
    for name in ("DensityLayer", "DensityProfile", "PowerLawSpectrum", "Spectrum", "TabulatedSpectrum",
                 "rayleigh_scattering_physical", "DOBSON_UNIT"):
        assert getattr(pp, name) is getattr(atmosphere, name)
    for name in ("solar_spectrum_astm_g173", "ozone_cross_section_serdyuchenko", "RayleighPhysicalSpectrum"):
        assert getattr(pp, name) is getattr(atmosphere.spectra, name)


def test_importing_the_atmosphere_imports_neither_numba_nor_colour():
    code = ("import sys, skyscatter.atmosphere; "
            "print(sorted(m for m in ('numba', 'colour', 'scipy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


# ------------------------------------------------------------------ constants


def test_standard_air_number_density_is_the_ideal_gas_at_288_15_k():
    """Bodhaine et al. (1999): N_s = p / (k T) at 1013.25 hPa and 288.15 K with the CODATA 1986 Boltzmann
    constant 1.380658e-23 J/K they used; the CODATA 2018 value (1.380649e-23, exact) gives 7e-6 more."""
    assert STANDARD_AIR_NUMBER_DENSITY == pytest.approx(101325.0 / (1.380658e-23 * 288.15), rel=1e-6)
    assert STANDARD_AIR_NUMBER_DENSITY == pytest.approx(101325.0 / (1.380649e-23 * 288.15), rel=1e-5)


def test_refractive_index_against_edlen_1966():
    """Peck & Reeder (1972) vs an independent dispersion formula for standard air, Edlen (1966), Metrologia 2,
    71, Eq. 1: (n - 1) 1e8 = 8342.13 + 2406030 / (130 - s^2) + 15997 / (38.9 - s^2); the two agree in n - 1
    to 1e-4 relative over 400-700 nm (Edlen's CO2 is 300 ppm too)."""
    s2 = (WL * 1e-3) ** -2
    edlen = 1e-8 * (8342.13 + 2406030.0 / (130.0 - s2) + 15997.0 / (38.9 - s2))
    np.testing.assert_allclose(refractive_index_standard_air(WL) - 1.0, edlen, rtol=1e-4)
    assert refractive_index_standard_air([550.0])[0] - 1.0 == pytest.approx(2.778e-4, rel=1e-3)


def test_one_king_factor_for_every_model():
    assert rayleigh_scattering_physical().king_factor == king_factor() == pytest.approx(1.0608, rel=1e-4)


def test_preetham_rayleigh_differs_from_standard_air_only_by_its_two_constants():
    """Preetham (1999) A.3 reproduces the physical formula with n = 1.0003 (no dispersion) and N = 2.545e25:
    the ratio to standard air is exactly ((1.0003^2 - 1) / (n_s^2 - 1))^2 N_s / N_P, 1.167 at 550 nm (n = 1.0003
    overstates n_s - 1 = 2.778e-4 by 8 %), 1.127 at 400 nm and 1.184 at 700 nm. N alone accounts for 0.075 %."""
    preetham = rayleigh_total_scattering_preetham1999(WL)
    physical = rayleigh_scattering_bodhaine1999(WL)
    n_s = refractive_index_standard_air(WL)
    n_p = AIR_REFRACTIVE_INDEX_PREETHAM1999
    expected = ((n_p**2 - 1.0) / (n_s**2 - 1.0)) ** 2 * STANDARD_AIR_NUMBER_DENSITY / AIR_NUMBER_DENSITY_PREETHAM1999
    np.testing.assert_allclose(preetham / physical, expected, rtol=1e-12)
    # ratios printed by the implementations before they shared code (separate modules, 2026-11)
    np.testing.assert_allclose((preetham / physical)[[0, 2, 4]], [1.1266, 1.1669, 1.1842], rtol=1e-4)
    assert STANDARD_AIR_NUMBER_DENSITY / AIR_NUMBER_DENSITY_PREETHAM1999 - 1.0 == pytest.approx(7.46e-4, rel=1e-2)
    # the physical spectrum of the precomputed model is the same function
    np.testing.assert_array_equal(rayleigh_scattering_physical()(WL), physical)


def test_one_data_loader_and_one_angstrom_formula():
    from skyscatter.atmosphere.tables import load_table

    solar = atmosphere.solar_spectrum_astm_g173()
    table = load_table("solar_spectrum_astm_g173")
    np.testing.assert_array_equal(solar.wavelengths, table["wavelength_nm"])
    ozone = atmosphere.ozone_cross_section_serdyuchenko()
    assert ozone(np.array([600.0]))[0] == pytest.approx(5.0e-25, rel=0.1)  # Chappuis maximum, ~5e-21 cm^2
    p = AtmosphereParameters.from_turbidity(4.0)
    assert p.mie_angstrom_beta == angstrom_beta(4.0) and p.mie_angstrom_alpha == atmosphere.ANGSTROM_ALPHA


# ------------------------------------------------------------------ phase functions


@pytest.mark.parametrize("kind", ["cornette-shanks", "henyey-greenstein"])
@pytest.mark.parametrize("g", [-0.5, 0.0, 0.3, 0.8, 0.95])
def test_phase_functions_integrate_to_one(kind, g):
    val, _ = integrate.quad(lambda c: 2 * np.pi * atmosphere.aerosol_phase(c, g, kind), -1, 1, points=[1.0],
                            limit=200)
    assert val == pytest.approx(1.0, abs=1e-9)
    val, _ = integrate.quad(lambda c: 2 * np.pi * rayleigh_phase(c), -1, 1)
    assert val == pytest.approx(1.0, abs=1e-12)


def test_numba_scalars_equal_the_numpy_functions():
    mu = np.linspace(-1.0, 1.0, 41)
    for g in (-0.4, 0.0, 0.8):
        for c in mu:
            assert phase_module.rayleigh_phase_scalar(c) == pytest.approx(rayleigh_phase(c), rel=1e-14)
            assert phase_module.henyey_greenstein_scalar(c, g) == pytest.approx(henyey_greenstein(c, g), rel=1e-14)
            assert phase_module.cornette_shanks_scalar(c, g) == pytest.approx(cornette_shanks(c, g), rel=1e-14)
            assert phase_module.aerosol_phase_scalar(c, g, 1) == phase_module.henyey_greenstein_scalar(c, g)
            assert phase_module.aerosol_phase_scalar(c, g, 0) == phase_module.cornette_shanks_scalar(c, g)
    with pytest.raises(AttributeError):
        phase_module.no_such_scalar  # noqa: B018


def test_cornette_shanks_mean_cosine():
    """Cornette & Shanks (1992): <cos> = 3 g (4 + g^2) / (5 (2 + g^2)) (not g); HG's mean cosine is g."""
    for g in (0.2, 0.8):
        m, _ = integrate.quad(lambda c, g=g: 2 * np.pi * c * cornette_shanks(c, g), -1, 1, points=[1.0], limit=200)
        assert m == pytest.approx(3 * g * (4 + g * g) / (5 * (2 + g * g)), rel=1e-8)
        m, _ = integrate.quad(lambda c, g=g: 2 * np.pi * c * henyey_greenstein(c, g), -1, 1, points=[1.0], limit=200)
        assert m == pytest.approx(g, rel=1e-8)


def test_cornette_shanks_over_henyey_greenstein_weight():
    """p_CS / p_HG = 3 (1 + mu^2) / (2 (2 + g^2)), bounded by [3 / (2 (2 + g^2)), 3 / (2 + g^2)] (attained at mu = 0
    and mu = +-1); checked against the two phase functions, which are tested against their integrals above."""
    mu = np.linspace(-1.0, 1.0, 201)
    for g in (-0.6, 0.0, 0.8, 0.95):
        w = phase_module.cornette_shanks_hg_weight(mu, g)
        np.testing.assert_allclose(w * henyey_greenstein(mu, g), cornette_shanks(mu, g), rtol=1e-13)
        lo, hi = 3 / (2 * (2 + g * g)), 3 / (2 + g * g)
        assert np.all(w >= lo * (1 - 1e-15)) and np.all(w <= hi * (1 + 1e-15))
        assert w[100] == pytest.approx(lo, rel=1e-15) and w[0] == pytest.approx(hi, rel=1e-15)
    with pytest.raises(InvalidParameterError):
        phase_module.cornette_shanks_hg_weight(0.5, 1.0)
    with pytest.raises(InvalidParameterError):
        phase_module.cornette_shanks_hg_weight(1.5, 0.8)


def _rayleigh_cdf(mu):
    return (mu**3 + 3 * mu + 4) / 8


def _hg_cdf(mu, g):
    return (1 - g * g) / (2 * g) * (1 / np.sqrt(1 + g * g - 2 * g * mu) - 1 / (1 + g))


def test_inverse_cdfs_invert_the_cdfs():
    u = np.linspace(0.0, 1.0, 1001)
    np.testing.assert_allclose(_rayleigh_cdf(rayleigh_inverse_cdf(u)), u, atol=1e-13)
    for g in (-0.7, 0.3, 0.9):
        np.testing.assert_allclose(_hg_cdf(henyey_greenstein_inverse_cdf(u, g), g), u, atol=1e-12)
    np.testing.assert_allclose(henyey_greenstein_inverse_cdf(u, 0.0), 2 * u - 1)
    assert rayleigh_inverse_cdf(0.0) == -1.0 and rayleigh_inverse_cdf(1.0) == pytest.approx(1.0, abs=1e-15)


def test_samples_follow_the_densities():
    """KS test of the exact inverse-CDF samplers against the analytic CDFs; chi-square test of the rejection
    sampler of Cornette-Shanks against bin probabilities integrated with scipy (20 bins, 20000 samples, fixed
    seed; a correct sampler fails with probability 1e-3)."""
    rng = np.random.default_rng(8)
    assert stats.kstest(sample_rayleigh(N_SAMPLES, rng), _rayleigh_cdf).pvalue > 1e-3
    for g in (-0.5, 0.8):
        assert stats.kstest(sample_henyey_greenstein(N_SAMPLES, g, rng), lambda m, g=g: _hg_cdf(m, g)).pvalue > 1e-3
    for g in (0.0, 0.5, 0.8):
        mu = sample_cornette_shanks(N_SAMPLES, g, rng)
        assert mu.shape == (N_SAMPLES,) and np.all(np.abs(mu) <= 1.0)
        edges = np.linspace(-1.0, 1.0, 21)
        probs = np.array([integrate.quad(lambda c, g=g: 2 * np.pi * cornette_shanks(c, g), a, b)[0]
                          for a, b in zip(edges[:-1], edges[1:], strict=True)])
        assert probs.sum() == pytest.approx(1.0, abs=1e-9)
        counts, _ = np.histogram(mu, edges)
        assert stats.chisquare(counts, probs * N_SAMPLES).pvalue > 1e-3
    # a wrong density is rejected by the same test (the test can fail)
    counts, _ = np.histogram(sample_henyey_greenstein(N_SAMPLES, 0.8, rng), edges)
    assert stats.chisquare(counts, probs * N_SAMPLES).pvalue < 1e-6


def test_sampler_shapes_and_errors():
    assert sample_rayleigh((3, 4), 0).shape == (3, 4)
    assert sample_cornette_shanks((2, 5), 0.8, 1).shape == (2, 5)
    assert sample_cornette_shanks(0, 0.8).shape == (0,)
    np.testing.assert_array_equal(sample_rayleigh(10, 5), sample_rayleigh(10, 5))
    with pytest.raises(InvalidParameterError):
        sample_henyey_greenstein(10, 1.0)
    with pytest.raises(InvalidParameterError):
        rayleigh_inverse_cdf([0.5, 1.5])
    with pytest.raises(InvalidParameterError):
        sample_rayleigh(-1)
    with pytest.raises(InvalidParameterError, match="henyey-greenstein"):
        atmosphere.aerosol_phase(0.5, 0.8, "mie")


# ------------------------------------------------------------------ the medium for a path tracer


def test_coefficients_at_altitude():
    p = AtmosphereParameters.from_turbidity(3.0)
    h = np.array([[0.0, 1200.0], [8000.0, 25_000.0]])
    ray, mie = p.scattering_coefficients(h, WL)
    assert ray.shape == mie.shape == (2, 2, WL.size)
    np.testing.assert_allclose(ray[0, 0], p.rayleigh_scattering_at(WL), rtol=1e-14)
    np.testing.assert_allclose(ray[1, 0], p.rayleigh_scattering_at(WL) * math.exp(-1.0), rtol=1e-14)
    np.testing.assert_allclose(mie[0, 1], p.mie_scattering_at(WL) * math.exp(-1.0), rtol=1e-14)
    absorption = p.absorption_coefficient(h, WL)
    ssa = p.mie_single_scattering_albedo
    np.testing.assert_allclose(absorption[1, 1], p.mie_extinction_at(WL) * (1 - ssa) * math.exp(-25_000 / 1200)
                               + p.ozone_absorption_at(WL), rtol=1e-12)  # ozone density 1 at 25 km
    np.testing.assert_allclose(p.extinction_coefficient(h, WL), ray + mie + absorption, rtol=1e-14)
    # scalar altitude, and 0 above the top of the atmosphere
    assert p.extinction_coefficient(0.0, [550.0]).shape == (1,)
    assert np.all(p.extinction_coefficient(p.thickness + 1.0, WL) == 0.0)
    for bad in (-1.0, np.nan):
        with pytest.raises(InvalidParameterError, match="altitude"):
            p.scattering_coefficients(bad, WL)
    with pytest.raises(InvalidParameterError):
        p.absorption_coefficient(0.0, [-550.0])


def test_vertical_columns_reproduce_the_defining_quantities():
    """Integrated over altitude (trapezoid, 0.25 m steps near the ground), aerosol extinction gives Angstrom's
    optical depth beta (lambda / 1 um)^-alpha (Preetham 1999, A.1) and ozone absorption / cross-section gives
    the ozone column in Dobson units (2.687e20 m^-2 each)."""
    p = AtmosphereParameters.from_turbidity(3.0, ozone_column=345.0)
    h = np.concatenate([np.linspace(0.0, 20_000.0, 80001), np.linspace(20_000.0, p.thickness, 40001)[1:]])
    wl = np.array([500.0, 600.0])
    ray, mie = p.scattering_coefficients(h, wl)
    mie_ext = mie / p.mie_single_scattering_albedo
    tau = np.trapezoid(mie_ext, h, axis=0)
    np.testing.assert_allclose(tau, angstrom_beta(3.0) * (wl / 1000.0) ** -1.3, rtol=1e-5)
    ozone = p.absorption_coefficient(h, wl) - mie_ext * (1 - p.mie_single_scattering_albedo)
    column = np.trapezoid(ozone, h, axis=0) / p.ozone_cross_section(wl)
    np.testing.assert_allclose(column / DOBSON_UNIT, 345.0, rtol=1e-5)
    # Rayleigh: H_R (1 - exp(-60/8)) metres of sea-level air
    np.testing.assert_allclose(np.trapezoid(ray, h, axis=0),
                               p.rayleigh_scattering_at(wl) * 8000.0 * (1 - math.exp(-60 / 8)), rtol=1e-6)


def test_phase_function_choice_validated_serialised_and_sampled():
    p = AtmosphereParameters(mie_phase_function="henyey-greenstein", mie_phase_g=0.7)
    q = AtmosphereParameters.from_dict(p.to_dict())
    assert q == p and q.to_dict()["mie_phase_function"] == "henyey-greenstein"
    np.testing.assert_array_equal(p.aerosol_phase([0.2, 0.9]), henyey_greenstein([0.2, 0.9], 0.7))
    np.testing.assert_array_equal(AtmosphereParameters().aerosol_phase(0.3), cornette_shanks(0.3, 0.8))
    np.testing.assert_array_equal(p.rayleigh_phase(0.3), rayleigh_phase(0.3))
    assert abs(np.mean(p.sample_aerosol_phase(N_SAMPLES, 3)) - 0.7) < 4 * 0.5 / math.sqrt(N_SAMPLES)
    assert abs(np.mean(p.sample_rayleigh_phase(N_SAMPLES, 4))) < 4 * 0.6 / math.sqrt(N_SAMPLES)
    for bad in ("mie", 3, None):
        with pytest.raises(InvalidParameterError, match="mie_phase_function|aerosol phase"):
            AtmosphereParameters(mie_phase_function=bad)
    # a description written before the field existed loads with the Cornette-Shanks phase it was made with
    old = AtmosphereParameters().to_dict()
    del old["mie_phase_function"]
    assert AtmosphereParameters.from_dict(old) == AtmosphereParameters()
    broken = AtmosphereParameters().to_dict()
    del broken["mie_phase_g"]
    with pytest.raises(FileFormatError):
        AtmosphereParameters.from_dict(broken)


def test_cache_key_depends_on_the_phase_function_and_keeps_old_keys():
    """The default (Cornette-Shanks) key is computed without the new field, so caches written before it
    still match; Henyey-Greenstein tables get another key."""
    import hashlib
    import json

    from skyscatter import __version__
    from skyscatter.precomputed.tables import FORMAT_VERSION, TableSizes, cache_key

    wl, sizes = np.array([680.0, 550.0, 440.0]), TableSizes()
    old = AtmosphereParameters().to_dict()
    del old["mie_phase_function"]
    blob = json.dumps({"params": old, "orders": 4, "wavelengths": [680.0, 550.0, 440.0],
                       "sizes": {f: getattr(sizes, f) for f in sizes.__dataclass_fields__},
                       "version": __version__, "format": FORMAT_VERSION}, sort_keys=True, separators=(",", ":"))
    assert cache_key(AtmosphereParameters(), 4, wl, sizes) == hashlib.sha256(blob.encode()).hexdigest()
    hg = AtmosphereParameters(mie_phase_function="henyey-greenstein")
    assert cache_key(hg, 4, wl, sizes) != cache_key(AtmosphereParameters(), 4, wl, sizes)


def test_precomputed_tables_honour_the_phase_function():
    """Aerosols only (no molecules, ozone or ground), one order: the sky radiance is the single-Mie table
    times the phase function, so the ratio of the Henyey-Greenstein sky to the Cornette-Shanks sky is the
    ratio of the two phase functions at the scattering angle (tables identical, 1e-6); with two orders the
    scattering density uses the chosen phase too, so the multiple-scattering tables differ."""
    from skyscatter.precomputed import PrecomputedAtmosphere

    tiny = dict(transmittance_mu=16, transmittance_r=4, irradiance_mu_s=4, irradiance_r=4, scattering_r=4,
                scattering_mu=8, scattering_mu_s=4, scattering_nu=4)
    base = AtmosphereParameters(rayleigh_scattering=0.0, ozone_column=0.0, ground_albedo=0.0, mie_phase_g=0.6)
    hg = base.replace(mie_phase_function="henyey-greenstein")
    wl = np.array([680.0, 550.0, 440.0])
    a = PrecomputedAtmosphere.compute(base, orders=1, wavelengths=wl, sizes=tiny, progress=False)
    b = PrecomputedAtmosphere.compute(hg, orders=1, wavelengths=wl, sizes=tiny, progress=False)
    np.testing.assert_array_equal(a.tables["single_mie"], b.tables["single_mie"])
    pos = np.array([0.0, 0.0, base.bottom_radius + 100.0])
    sun = np.array([0.0, math.sin(0.6), math.cos(0.6)])
    zen = np.radians([10.0, 40.0, 70.0])
    dirs = np.stack([np.sin(zen), np.zeros(3), np.cos(zen)], axis=-1)  # az 90 deg from the sun
    nu = dirs @ sun
    ra = a.sky_radiance(pos, dirs, sun, include_ground=False)
    rb = b.sky_radiance(pos, dirs, sun, include_ground=False)
    assert np.all(ra > 0)
    ratio = henyey_greenstein(nu, 0.6) / cornette_shanks(nu, 0.6)
    np.testing.assert_allclose(rb / ra, np.broadcast_to(ratio[:, None], ra.shape),
                               rtol=1e-6)
    a2 = PrecomputedAtmosphere.compute(base, orders=2, wavelengths=wl, sizes=tiny, progress=False)
    b2 = PrecomputedAtmosphere.compute(hg, orders=2, wavelengths=wl, sizes=tiny, progress=False)
    assert not np.allclose(a2.tables["multiple"], b2.tables["multiple"], rtol=1e-3)


def test_former_names_are_aliases():
    assert atmosphere.relative_optical_mass is atmosphere.relative_optical_mass_kasten1966
    assert atmosphere.rayleigh_total_scattering is rayleigh_total_scattering_preetham1999
    assert atmosphere.rayleigh_angular_scattering is atmosphere.rayleigh_angular_scattering_preetham1999
    assert atmosphere.AIR_NUMBER_DENSITY == AIR_NUMBER_DENSITY_PREETHAM1999 == 2.545e25
    assert atmosphere.AIR_REFRACTIVE_INDEX == AIR_REFRACTIVE_INDEX_PREETHAM1999 == 1.0003
