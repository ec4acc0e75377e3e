"""AtmosphereParameters: Earth defaults, derived coefficients and validation (Bruneton & Neyret 2008, Sec. 2.1)."""

import math

import numpy as np
import pytest

from skyscatter.errors import InvalidParameterError
from skyscatter.precomputed import (
    AtmosphereParameters,
    DensityProfile,
    TableSizes,
    TabulatedSpectrum,
    rayleigh_scattering_physical,
)

WL = np.array([680.0, 550.0, 440.0])


def test_earth_default_coefficients_match_seeds_readme():
    """Seeds README (Bruneton 2017 Earth defaults): beta_R, Mie scattering / extinction, ozone peak, 4 sig. digits."""
    p = AtmosphereParameters()
    np.testing.assert_allclose(p.rayleigh_scattering_at(WL), [5.802e-6, 13.558e-6, 33.100e-6], rtol=2e-4)
    np.testing.assert_allclose(p.mie_scattering_at(WL), 3.996e-6, rtol=1e-6)
    np.testing.assert_allclose(p.mie_extinction_at(WL), 4.44e-6, rtol=1e-6)
    np.testing.assert_allclose(p.ozone_absorption_at(WL), [0.650e-6, 1.881e-6, 0.085e-6], rtol=1e-3)
    assert p.ground_albedo_at(WL).tolist() == [0.1, 0.1, 0.1]
    assert p.sun_angular_radius == 0.004675
    assert math.isclose(math.degrees(p.max_sun_zenith), 102.0)
    assert (p.bottom_radius, p.top_radius) == (6_360_000.0, 6_420_000.0)


def test_density_profiles():
    """Exponential layers (Eqs. 1, 3) and the ozone tent: values and columns."""
    exp = DensityProfile.exponential(8000.0)
    np.testing.assert_allclose(exp([0.0, 8000.0]), [1.0, math.exp(-1)], rtol=1e-12)
    assert math.isclose(exp.column(60_000.0), 8000.0 * (1 - math.exp(-7.5)), rel_tol=1e-8)
    tent = DensityProfile.tent(10e3, 25e3, 40e3)
    np.testing.assert_allclose(tent([0.0, 10e3, 17.5e3, 25e3, 32.5e3, 40e3, 50e3]), [0, 0, 0.5, 1, 0.5, 0, 0],
                               atol=1e-12)
    assert math.isclose(tent.column(60e3), 15e3, rel_tol=1e-9)


def test_solar_irradiance_is_box_averaged_astm_g173():
    """The ASTM G173 ETR averaged over 10 nm: 1.8-2.0 W m^-2 nm^-1 in the visible (Gueymard 2004)."""
    e = AtmosphereParameters().solar_irradiance_at(WL)
    assert np.all((e > 1.4) & (e < 2.1))
    # the band average of a constant spectrum is the constant
    p = AtmosphereParameters(solar_irradiance=1.5)
    np.testing.assert_allclose(p.solar_irradiance_at(WL), 1.5, rtol=1e-12)


def test_physical_rayleigh_against_preetham_a1():
    """Rayleigh from the refractive index (King factor 1.061 for p_n = 0.035) vs Preetham 1999 A.1,
    tau_R = 0.008735 lambda_um^-4.08 for one air mass, using the standard-atmosphere column (p0 / (rho0 g) =
    8434 m of sea-level air): agreement within 3 % over 400-700 nm."""
    rs = rayleigh_scattering_physical()
    assert math.isclose(rs.king_factor, 1.0608, rel_tol=1e-3)
    wl = np.array([400.0, 450.0, 550.0, 700.0])
    tau = rs(wl) * 101325 / (1.225 * 9.80665)
    np.testing.assert_allclose(tau, 0.008735 * (wl / 1000) ** -4.08, rtol=0.03)


def test_turbidity_mapping():
    """Preetham 1999 A.1: alpha 1.3, beta = 0.04608 T - 0.04586; optical depth = beta lambda_um^-alpha."""
    p = AtmosphereParameters.from_turbidity(3.0)
    beta = 0.04608 * 3 - 0.04586
    tau = p.mie_extinction_at(np.array([500.0])) * p.mie_density.column(p.thickness)
    np.testing.assert_allclose(tau, beta * 0.5**-1.3, rtol=1e-9)
    with pytest.raises(InvalidParameterError, match="turbidity"):
        AtmosphereParameters.from_turbidity(0.5)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"top_radius": 6_000_000.0}, "top_radius"),
        ({"bottom_radius": -1.0}, "bottom_radius"),
        ({"mie_phase_g": 1.0}, "mie_phase_g"),
        ({"mie_phase_g": -1.2}, "mie_phase_g"),
        ({"mie_angstrom_beta": -0.1}, "mie_angstrom_beta"),
        ({"rayleigh_scattering": -1e-6}, ">= 0"),
        ({"ozone_column": -5.0}, "ozone_column"),
        ({"mie_single_scattering_albedo": 1.5}, "single_scattering_albedo"),
        ({"max_sun_zenith": math.radians(95.0)}, "102"),
        ({"sun_angular_radius": float("nan")}, "finite"),
    ],
)
def test_invalid_parameters_are_refused(changes, message):
    with pytest.raises(InvalidParameterError, match=message):
        AtmosphereParameters(**changes)


def test_invalid_albedo_and_spectra():
    with pytest.raises(InvalidParameterError, match="albedo"):
        AtmosphereParameters(ground_albedo=1.5).ground_albedo_at(WL)
    with pytest.raises(InvalidParameterError, match="increasing"):
        TabulatedSpectrum((500.0, 400.0), (1.0, 1.0))
    with pytest.raises(InvalidParameterError, match="tabulated for 360-830 nm"):
        AtmosphereParameters().check_wavelengths([300.0])


def test_serialisation_round_trip_and_hashable():
    p = AtmosphereParameters.from_turbidity(2.5, ground_albedo=0.3, rayleigh_scattering=rayleigh_scattering_physical())
    q = AtmosphereParameters.from_dict(p.to_dict())
    assert q == p and hash(q) == hash(p)
    assert p.canonical_json() == q.canonical_json()
    assert AtmosphereParameters() != p


def test_table_sizes_validation():
    assert TableSizes().scattering_shape == (32, 128, 32, 8)
    assert TableSizes.coerce({"scattering_r": 8}).scattering_r == 8
    with pytest.raises(InvalidParameterError, match="even"):
        TableSizes(scattering_mu=31)
    with pytest.raises(InvalidParameterError, match=">= 2"):
        TableSizes(scattering_nu=1)
    with pytest.raises(InvalidParameterError, match="unknown"):
        TableSizes.coerce({"scatering_r": 8})


def test_solar_spectrum_too_narrow_for_colour_conversion_is_refused():
    """Few-wavelength mode rebuilds spectra over 360-830 nm: the solar spectrum must cover 355-835 nm, and a
    narrower one is refused by compute() (before any work), naming that range; the spectral mode integrates
    the table wavelengths only and accepts it."""
    from skyscatter.precomputed import PrecomputedAtmosphere

    wl = np.arange(380.0, 781.0, 10.0)
    narrow = AtmosphereParameters(solar_irradiance=TabulatedSpectrum(tuple(wl), tuple(np.full(wl.size, 1.5))))
    with pytest.raises(InvalidParameterError, match=r"covers 380-780 nm.*must cover 355-835 nm"):
        PrecomputedAtmosphere.compute(narrow, orders=1, progress=False, tables="rgb")
    tiny = dict(transmittance_mu=16, transmittance_r=4, irradiance_mu_s=4, irradiance_r=4, scattering_r=4,
                scattering_mu=8, scattering_mu_s=4, scattering_nu=4)
    atm = PrecomputedAtmosphere.compute(narrow, orders=1, wavelengths=np.arange(390.0, 771.0, 20.0), sizes=tiny,
                                        progress=False)
    assert atm.spectral_mode and np.all(np.isfinite(atm.xyz_matrix))
