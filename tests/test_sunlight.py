"""Sunlight at the ground: Preetham, Shirley & Smits (1999) A.1 and Table 2, cross-checked with SPECTRL2."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyscatter.atmosphere import angstrom_beta, rayleigh_total_scattering, relative_optical_mass
from skyscatter.atmosphere.tables import tabulated
from skyscatter.errors import InvalidParameterError
from skyscatter.sky.base import solar_disc_solid_angle
from skyscatter.spectral import REFERENCE_WAVELENGTHS, spectrum_to_xyz
from skyscatter.sun.sunlight import (
    extraterrestrial_radiance,
    sun_direct_normal_irradiance,
    sun_spectral_radiance,
    transmittances,
)


def _astm_band_means(centres: np.ndarray) -> np.ndarray:
    """10-nm band means (centred) of the ASTM G173-03 extraterrestrial spectrum [W m^-2 nm^-1]."""
    from pvlib.spectrum import get_reference_spectra

    ref = get_reference_spectra(standard="ASTM G173-03")
    w, et = ref.index.to_numpy(float), ref["extraterrestrial"].to_numpy(float)
    out = []
    for c in centres:
        x = np.linspace(c - 5.0, c + 5.0, 201)
        out.append(np.trapezoid(np.interp(x, w, et), x) / 10.0)
    return np.array(out)


# ---------------------------------------------------------------- extraterrestrial spectrum
def test_extraterrestrial_at_500nm():
    # seeds errata: Table 2 "Sun rad." times the ~6.8e-5 sr disc gives about 1.9 W m^-2 nm^-1 at 500 nm
    e500 = extraterrestrial_radiance([500.0])[0] * solar_disc_solid_angle()
    assert e500 == pytest.approx(1.95, abs=0.05)
    assert sun_direct_normal_irradiance(0.0, 1.0, [500.0])[0] < e500


def test_table2_sun_radiance_units():
    # The factor-of-10 check: Table 2 / (ASTM G173 band mean) must be 1 / (solid angle of the sun), and every
    # row must agree: measured 1/ratio = 6.45e-5 .. 7.32e-5 sr against the disc's 6.74-6.87e-5 sr.
    wl, sun = tabulated("preetham1999_table2", "sun_radiance")
    omega = _astm_band_means(wl) / sun
    assert np.all((omega > 6.2e-5) & (omega < 7.5e-5))
    assert omega.mean() == pytest.approx(solar_disc_solid_angle(), rel=0.03)


def test_extension_rederived_from_astm_g173():
    # data/preetham1999_table2_extension.csv: ASTM band means scaled to Table 2 over 380-420 and 700-750 nm
    wl, sun = tabulated("preetham1999_table2", "sun_radiance")
    xe, ye = tabulated("preetham1999_table2_extension", "sun_radiance")
    blue = (wl >= 380) & (wl <= 420)
    red = (wl >= 700) & (wl <= 750)
    f_blue = np.mean(sun[blue] / _astm_band_means(wl[blue]))
    f_red = np.mean(sun[red] / _astm_band_means(wl[red]))
    expected = np.where(xe < 380, f_blue, f_red) * _astm_band_means(xe)
    np.testing.assert_allclose(ye, expected, rtol=1e-4)


def test_extraterrestrial_covers_cie_range_continuously():
    e = extraterrestrial_radiance(REFERENCE_WAVELENGTHS)
    assert np.all(np.isfinite(e)) and np.all(e > 1e4)
    # no jump at the joins: neighbours within the spectrum's own 10-nm variability (< 30 %)
    assert np.all(np.abs(np.diff(np.log(e))) < 0.3)


def test_extraterrestrial_illuminance():
    # Solar illuminance constant 133.3 klx (Darula, Kittler & Gueymard 2005); measured 129.3 klx (-3 %).
    wl = REFERENCE_WAVELENGTHS
    ev = spectrum_to_xyz(extraterrestrial_radiance(wl) * solar_disc_solid_angle(), wl)[1]
    assert ev == pytest.approx(133.3e3, rel=0.05)


# ---------------------------------------------------------------- transmittances
ZENITHS = np.radians([0.0, 20.0, 45.0, 60.0, 75.0, 85.0, 89.5])


@pytest.mark.parametrize("turbidity", [1.0, 2.0, 6.0, 20.0])
def test_transmittances_bounded_and_decreasing_with_air_mass(turbidity):
    taus = transmittances(ZENITHS, REFERENCE_WAVELENGTHS, turbidity)
    for name, tau in taus._asdict().items():
        assert tau.shape == (ZENITHS.size, REFERENCE_WAVELENGTHS.size), name
        assert np.all(tau > 0) and np.all(tau <= 1), name
        assert np.all(np.diff(tau, axis=0) <= 0), name  # air mass grows with zenith


def test_transmittance_values():
    taus = transmittances(0.0, [550.0, 700.0, 720.0, 760.0], 2.0)
    m = relative_optical_mass(0.0)
    # A.1 Rayleigh: 0.008735 * 0.55^-4.08 = 0.1001 optical depth
    assert taus.rayleigh[0] == pytest.approx(math.exp(-0.008735 * 0.55**-4.08 * m))
    # ozone at 550 nm: k_o = 8.5 m^-1 (Table 2), l = 0.0035 m
    assert taus.ozone[0] == pytest.approx(math.exp(-8.5 * 0.0035 * m))
    # absorption bands: water vapour at 720 nm, oxygen A band at 760 nm; none at 550 nm
    assert taus.water_vapour[0] == 1.0 and taus.mixed_gases[0] == 1.0
    assert taus.water_vapour[2] < 0.95 and taus.mixed_gases[3] < 0.8  # 0.914 and 0.74 from A.1
    # pure air: (almost) no aerosol extinction; beta(T = 1) = 0.00022
    assert np.all(transmittances(0.0, [550.0], 1.0).aerosol > 0.999)


def test_rayleigh_transmittance_against_scattering_coefficient():
    # A.1's fitted Rayleigh optical depth against A.3's coefficient times a homogeneous-atmosphere height of
    # 8.4 km (course notes: molecular optical length at the zenith); measured ratio 0.88 at 400-700 nm.
    wl = np.array([400.0, 550.0, 700.0])
    tau_a1 = -np.log(transmittances(0.0, wl, 1.0).rayleigh) / relative_optical_mass(0.0)
    tau_a3 = rayleigh_total_scattering(wl) * 8400.0
    np.testing.assert_allclose(tau_a1 / tau_a3, 0.88, atol=0.05)


def test_below_horizon_zero_and_nan_refused():
    spec = sun_spectral_radiance(np.radians([89.0, 90.0, 120.0]), 3.0, REFERENCE_WAVELENGTHS)
    assert np.all(spec[0] > 0)
    assert np.all(spec[1:] == 0)
    with pytest.raises(InvalidParameterError, match="NaN"):
        sun_spectral_radiance(float("nan"), 2.0)
    with pytest.raises(InvalidParameterError, match=r"\[0, pi\]"):
        sun_spectral_radiance(-0.1, 2.0)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(turbidity=0.5), ">= 1"),
        (dict(turbidity=float("inf")), ">= 1"),
        (dict(turbidity=2.0, wavelengths=[300.0, 500.0]), "360, 830"),
        (dict(turbidity=2.0, ozone=-0.001), "ozone"),
        (dict(turbidity=2.0, water_vapour=0.5), "water vapour"),
    ],
)
def test_bad_parameters(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        sun_spectral_radiance(0.5, **kwargs)


def test_never_nan_over_reference_grid_and_shapes():
    zen = np.linspace(0.0, np.pi, 37).reshape(37, 1) * np.ones((1, 2))
    spec = sun_spectral_radiance(zen, 2.5, REFERENCE_WAVELENGTHS)
    assert spec.shape == (37, 2, REFERENCE_WAVELENGTHS.size)
    assert np.all(np.isfinite(spec)) and np.all(spec >= 0)
    assert sun_spectral_radiance(0.3, 2.0).shape == (41,)
    dni = sun_direct_normal_irradiance(0.3, 2.0, [550.0])
    assert dni[0] == pytest.approx(sun_spectral_radiance(0.3, 2.0, [550.0])[0] * solar_disc_solid_angle())


def test_sun_illuminance_and_colour_high_sun():
    # plausibility: clear-sky direct normal illuminance at high sun is about 100 klx; the noon sun's
    # chromaticity near (0.33, 0.34) (about 5600 K). Measured T = 2, zenith 0: 102.8 klx, (0.330, 0.340).
    wl = REFERENCE_WAVELENGTHS
    xyz = spectrum_to_xyz(sun_direct_normal_irradiance(0.0, 2.0, wl), wl)
    assert xyz[1] == pytest.approx(100e3, rel=0.1)
    x, y = xyz[0] / xyz.sum(), xyz[1] / xyz.sum()
    assert x == pytest.approx(0.33, abs=0.01) and y == pytest.approx(0.34, abs=0.01)
    # a low sun is redder
    xyz_low = spectrum_to_xyz(sun_direct_normal_irradiance(math.radians(85.0), 2.0, wl), wl)
    assert xyz_low[0] / xyz_low.sum() > x + 0.05


# ------------------------------------------------------- SPECTRL2 (Bird & Riordan 1986) through pvlib
def _spectrl2(zenith_deg: float, turbidity: float):
    from pvlib.irradiance import get_extra_radiation
    from pvlib.spectrum import spectrl2

    days = np.arange(1, 366)
    day = int(days[np.argmin(np.abs(get_extra_radiation(days, method="spencer", solar_constant=1) - 1))])
    m = relative_optical_mass(math.radians(zenith_deg))
    result = spectrl2(
        apparent_zenith=zenith_deg, aoi=0.0, surface_tilt=0.0, ground_albedo=0.2, surface_pressure=101325.0,
        relative_airmass=m, precipitable_water=2.0, ozone=0.35,
        aerosol_turbidity_500nm=angstrom_beta(turbidity) * 0.5**-1.3, alpha=1.3, dayofyear=day,
    )
    wl = np.asarray(result["wavelength"], dtype=float)
    sel = (wl >= 400.0) & (wl <= 700.0)
    dni = np.asarray(result["dni"], dtype=float).ravel()[sel]
    extra = np.asarray(result["dni_extra"], dtype=float).ravel()[sel]
    return wl[sel], dni, extra


CASES = [(20.0, 2.0), (30.0, 3.0), (60.0, 2.0)]


@pytest.mark.parametrize(("zenith_deg", "turbidity"), CASES)
def test_transmittance_matches_spectrl2(zenith_deg, turbidity):
    # Same air mass (Kasten), Earth-Sun distance 1 AU, ozone 0.35 atm-cm, water 2 cm, aerosol optical depth at
    # 500 nm = beta 0.5^-1.3 with alpha 1.3. Measured product of transmittances: within 0.4 % of SPECTRL2's
    # dni / dni_extra except at 593 nm (+1.9 %, SPECTRL2 has a weak water line) and 690 nm (+6 %, SPECTRL2 has
    # the O2 B band; Table 2 has no k_g there).
    wl, dni, extra = _spectrl2(zenith_deg, turbidity)
    taus = transmittances(math.radians(zenith_deg), wl, turbidity)
    ours = taus.rayleigh * taus.aerosol * taus.ozone * taus.mixed_gases * taus.water_vapour
    rel = ours / (dni / extra) - 1.0
    lines = np.isin(wl, [593.0, 690.0])
    assert np.all(np.abs(rel[~lines]) < 0.01)
    assert np.all(np.abs(rel[lines]) < 0.1)


@pytest.mark.parametrize(("zenith_deg", "turbidity"), CASES)
def test_direct_normal_irradiance_matches_spectrl2(zenith_deg, turbidity):
    # Per band (SPECTRL2's own wavelengths, 400-700 nm) the measured differences are -7.8 % .. +8.8 %, almost
    # all from the two extraterrestrial spectra (Table 2 after Coulson/NASA 1975 vs SPECTRL2's; they differ by
    # -7.4 % at 550 nm and +4.8 % at 430 nm) and the 690 nm O2 band. Tolerance 10 % per band; over 400-700 nm
    # the integrals agree to 1.1 % (tolerance 3 %).
    wl, dni, _ = _spectrl2(zenith_deg, turbidity)
    ours = sun_direct_normal_irradiance(math.radians(zenith_deg), turbidity, wl)
    rel = ours / dni - 1.0
    assert np.all(np.abs(rel) < 0.10)
    assert np.trapezoid(ours, wl) / np.trapezoid(dni, wl) == pytest.approx(1.0, abs=0.03)


@pytest.mark.parametrize(
    ("turbidity", "ozone", "water"), [(2.0, 0.0035, 0.02), (7.5, 0.003, 0.045), (1.0, 0.0, 0.0)]
)
def test_radiance_is_extraterrestrial_times_transmittances(turbidity, ozone, water):
    # sun_spectral_radiance sums the optical depths and takes one exponential; transmittances() evaluates the
    # five factors of A.1 one by one: the two code paths must agree
    wl = REFERENCE_WAVELENGTHS
    zen = np.radians([0.0, 35.0, 70.0, 89.9, 90.0, 95.0])
    taus = transmittances(zen, wl, turbidity, ozone=ozone, water_vapour=water)
    product = taus.rayleigh * taus.aerosol * taus.ozone * taus.mixed_gases * taus.water_vapour
    expected = extraterrestrial_radiance(wl) * product
    got = sun_spectral_radiance(zen, turbidity, wl, ozone=ozone, water_vapour=water)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0.0)


def test_property_transmittances_fall_with_turbidity_and_stay_in_unit_interval():
    from hypothesis import given, settings
    from hypothesis import strategies as st

    @settings(max_examples=40, deadline=None)
    @given(
        zenith=st.floats(0.0, math.radians(89.9)),
        turbidity=st.floats(1.0, 30.0),
        extra=st.floats(0.01, 5.0),
        wavelength=st.floats(360.0, 830.0),
    )
    def check(zenith, turbidity, extra, wavelength):
        a = sun_spectral_radiance(zenith, turbidity, [wavelength])[0]
        b = sun_spectral_radiance(zenith, turbidity + extra, [wavelength])[0]
        et = extraterrestrial_radiance([wavelength])[0]
        assert 0.0 < b <= a <= et
        for tau in transmittances(zenith, [wavelength], turbidity):
            assert 0.0 < tau[0] <= 1.0

    check()
