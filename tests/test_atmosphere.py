"""Atmosphere optics: phase functions, Rayleigh and Mie (Preetham 1999 A.3), optical mass, turbidity."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyscatter.atmosphere import (
    ANGSTROM_ALPHA,
    angstrom_beta,
    cornette_shanks,
    eta_integral_ratio,
    haze_concentration,
    henyey_greenstein,
    king_factor,
    meteorological_range,
    mie_angular_scattering,
    mie_eta,
    mie_k,
    mie_phase_function,
    mie_total_scattering,
    rayleigh_angular_scattering,
    rayleigh_phase,
    rayleigh_total_scattering,
    relative_optical_mass,
    turbidity_from_meteorological_range,
)
from skyscatter.atmosphere.tables import load_table
from skyscatter.errors import InvalidParameterError

MU = np.linspace(-1.0, 1.0, 200001)
THETA = np.linspace(0.0, np.pi, 20001)
WL = np.array([400.0, 450.0, 550.0, 650.0, 780.0])


def sphere_integral_mu(values: np.ndarray) -> np.ndarray:
    """2 pi times the integral over cos(theta) in [-1, 1] (axis 0)."""
    return 2.0 * np.pi * np.trapezoid(values, MU, axis=0)


def sphere_integral_theta(values: np.ndarray) -> np.ndarray:
    """2 pi times the integral of values sin(theta) dtheta over [0, pi] (axis 0)."""
    return 2.0 * np.pi * np.trapezoid(values * np.sin(THETA)[:, None], THETA, axis=0)


# ---------------------------------------------------------------- phase functions
@pytest.mark.parametrize("g", [-0.7, 0.0, 0.3, 0.76])
def test_phase_functions_normalised_and_mean_cosine(g):
    assert sphere_integral_mu(rayleigh_phase(MU)) == pytest.approx(1.0, abs=1e-9)
    hg = henyey_greenstein(MU, g)
    cs = cornette_shanks(MU, g)
    assert sphere_integral_mu(hg) == pytest.approx(1.0, abs=1e-6)
    assert sphere_integral_mu(cs) == pytest.approx(1.0, abs=1e-6)
    # Henyey-Greenstein's defining property: mean cosine = g
    assert sphere_integral_mu(MU * hg) == pytest.approx(g, abs=1e-6)
    assert np.all(hg > 0) and np.all(cs > 0)


def test_phase_function_special_values():
    assert rayleigh_phase(1.0) == pytest.approx(3.0 / (8.0 * np.pi))
    assert henyey_greenstein(0.3, 0.0) == pytest.approx(1.0 / (4.0 * np.pi))
    # Cornette-Shanks reduces to the Rayleigh phase function for g = 0
    np.testing.assert_allclose(cornette_shanks(MU[::1000], 0.0), rayleigh_phase(MU[::1000]), rtol=1e-12)
    assert henyey_greenstein(np.ones((2, 3)), 0.5).shape == (2, 3)


@pytest.mark.parametrize("g", [1.0, -1.0, 1.5, float("nan")])
def test_phase_function_bad_g(g):
    with pytest.raises(InvalidParameterError, match="g must be in"):
        henyey_greenstein(0.5, g)
    with pytest.raises(InvalidParameterError, match="g must be in"):
        cornette_shanks(0.5, g)


def test_phase_function_bad_cosine():
    with pytest.raises(InvalidParameterError, match=r"\[-1, 1\]"):
        rayleigh_phase([0.0, 1.5])
    with pytest.raises(InvalidParameterError):
        henyey_greenstein(float("nan"), 0.5)


# ---------------------------------------------------------------- Rayleigh
def test_king_factor():
    # Preetham 1999 A.3 with the standard p_n = 0.035 (seeds errata: about 1.061)
    assert king_factor() == pytest.approx(1.061, abs=5e-4)
    assert king_factor(0.0) == 1.0
    with pytest.raises(InvalidParameterError):
        king_factor(0.9)


def test_rayleigh_against_published_sea_level_values():
    # Bruneton & Neyret 2008 / Bruneton 2017 defaults: (5.802, 13.558, 33.100)e-6 m^-1 at (680, 550, 440) nm
    beta = rayleigh_total_scattering([680.0, 550.0, 440.0])
    np.testing.assert_allclose(beta, [5.802e-6, 13.558e-6, 33.100e-6], rtol=0.01)


def test_rayleigh_lambda_minus_four():
    beta = rayleigh_total_scattering([400.0, 800.0])
    assert beta[0] / beta[1] == pytest.approx(16.0, rel=1e-12)


def test_rayleigh_angular_matches_paper_form_and_integrates_to_total():
    n, big_n, p = 1.0003, 2.545e25, 0.035
    lam = WL * 1e-9
    theta = np.array([0.0, 0.7, np.pi / 2, 2.5, np.pi])
    # A.3, angular coefficient written out as in the paper
    paper = (np.pi**2 * (n * n - 1) ** 2 / (2 * big_n * lam**4) * (6 + 3 * p) / (6 - 7 * p)
             * (1 + np.cos(theta)[:, None] ** 2))
    np.testing.assert_allclose(rayleigh_angular_scattering(theta, WL), paper, rtol=1e-12)
    total = sphere_integral_theta(rayleigh_angular_scattering(THETA, WL))
    np.testing.assert_allclose(total, rayleigh_total_scattering(WL), rtol=1e-7)


def test_rayleigh_shapes_and_errors():
    assert rayleigh_angular_scattering(np.zeros((2, 3)), WL).shape == (2, 3, WL.size)
    assert rayleigh_angular_scattering(0.3, WL).shape == (WL.size,)
    with pytest.raises(InvalidParameterError):
        rayleigh_angular_scattering(4.0, WL)
    with pytest.raises(InvalidParameterError):
        rayleigh_total_scattering([-550.0])
    with pytest.raises(InvalidParameterError):
        rayleigh_total_scattering(WL, refractive_index=0.9)


# ---------------------------------------------------------------- Mie (haze)
def test_haze_concentration():
    # A.3: c = (0.6544 T - 0.6510) 1e-16; course notes: 6e-17 .. 25e-17 from clear to overcast
    assert haze_concentration(2.0) == pytest.approx(0.6578e-16)
    assert 6e-17 <= haze_concentration(2.0) <= 25e-17
    with pytest.raises(InvalidParameterError, match=">= 1"):
        haze_concentration(0.5)


def test_mie_magnitude_against_angstrom_relation():
    # Independent of A.3: A.1's Angstrom coefficients (beta = 0.04608 T - 0.04586, alpha = 1.3) give the
    # aerosol optical depth at 550 nm; with the paper's haze scale height 1/alpha_haze = 1.2 km (A.4) the
    # sea-level coefficient is tau / 1200 m. Measured ratio A.3 / Angstrom: 0.945 for T = 2..10.
    for turbidity in (2.0, 4.0, 6.0, 10.0):
        beta_p = mie_total_scattering([550.0], turbidity)[0]
        tau_angstrom = angstrom_beta(turbidity) * 0.55**-ANGSTROM_ALPHA
        assert beta_p / (tau_angstrom / 1200.0) == pytest.approx(1.0, abs=0.1)
    beta_2 = mie_total_scattering([550.0], 2.0)[0]
    assert 1e-5 < beta_2 < 1e-4  # haze at sea level, not fog (the literal SI reading gives 7.9e-3 m^-1)
    assert beta_2 == pytest.approx(7.94e-5, rel=0.01)


def test_mie_magnitude_against_turbidity_definition():
    # T = (t_m + t_h) / t_m with vertical optical depths t = beta(0) H, H_m = 1/0.1136 km^-1, H_h = 1/0.8333
    # km^-1 (A.4). Measured: the implied (T - 1) is 0.80 (T - 1) at 550 nm, for every T.
    beta_m = rayleigh_total_scattering([550.0])[0]
    for turbidity in (2.0, 3.0, 6.0):
        t_h = mie_total_scattering([550.0], turbidity)[0] / 0.8333e-3
        t_m = beta_m / 0.1136e-3
        assert (t_h / t_m) / (turbidity - 1.0) == pytest.approx(0.8, abs=0.1)


def test_mie_eta_reproduces_table_nodes():
    table = load_table("preetham1999_table1_mie_eta")
    theta = np.radians(table["theta_deg"])
    eta = mie_eta(theta, [400.0, 450.0, 550.0, 650.0, 850.0])
    expected = np.stack([table[f"eta_{w}"] for w in (400, 450, 550, 650, 850)], axis=-1)
    np.testing.assert_allclose(eta, expected, rtol=1e-12)
    # 500 nm lies halfway between the 450 and 550 columns
    halfway = 0.5 * (expected[:, 1] + expected[:, 2])
    np.testing.assert_allclose(mie_eta(theta, [500.0])[:, 0], halfway, rtol=1e-12)


def test_eta_and_k_tables_consistent():
    # Table 1 (eta) and Table 2 (K) describe the same haze: integral eta sin dtheta = K. Measured 1.005.
    ratio = eta_integral_ratio(WL)
    np.testing.assert_allclose(ratio, 1.005, atol=0.01)
    # the angular coefficient integrates to that ratio times the total coefficient (quadrature cross-check)
    integral = sphere_integral_theta(mie_angular_scattering(THETA, WL, 3.0))
    np.testing.assert_allclose(integral / mie_total_scattering(WL, 3.0), ratio, rtol=1e-4)


def test_mie_phase_function_normalised_and_forward_peaked():
    p = mie_phase_function(THETA, WL)
    np.testing.assert_allclose(sphere_integral_theta(p), 1.0, rtol=1e-4)
    assert np.all(p[0] > 20 * p[len(THETA) // 2])
    assert np.all(p >= 0)


def test_mie_properties_and_shapes():
    beta = mie_total_scattering(WL, 3.0)
    assert np.all(np.diff(beta) < 0)  # more scattering in the blue (lambda^-2 K)
    assert np.all(mie_total_scattering(WL, 4.0) > beta)  # grows with turbidity
    assert mie_angular_scattering(np.zeros((4, 2)), WL, 2.0).shape == (4, 2, WL.size)
    # K held constant outside the table (380-780 nm), never NaN
    k = mie_k([360.0, 380.0, 830.0])
    assert k[0] == k[1] and np.all(np.isfinite(k))
    assert np.all(np.isfinite(mie_angular_scattering(THETA[::100], [360.0, 830.0], 2.0)))


# ---------------------------------------------------------------- optical mass
def test_relative_optical_mass():
    from pvlib.atmosphere import get_relative_airmass

    zen_deg = np.array([0.0, 30.0, 60.0, 80.0, 85.0, 89.0, 90.0])
    m = relative_optical_mass(np.radians(zen_deg))
    # an independent implementation of the same Kasten (1966) formula
    np.testing.assert_allclose(m, get_relative_airmass(zen_deg, model="kasten1966"), rtol=1e-9)
    # plane-parallel limit sec(theta) for a high sun
    sec30 = 1.0 / math.cos(math.radians(30.0))
    assert relative_optical_mass(math.radians(30.0)) == pytest.approx(sec30, rel=2e-3)
    assert np.all(np.diff(m) > 0)
    assert 30 < m[-1] < 40  # the horizon air mass of the Kasten form (about 36.5)
    assert isinstance(relative_optical_mass(0.3), float)
    with pytest.raises(InvalidParameterError):
        relative_optical_mass(2.0)


# ---------------------------------------------------------------- turbidity
def test_angstrom_beta():
    assert angstrom_beta(2.0) == pytest.approx(0.04608 * 2 - 0.04586)
    assert ANGSTROM_ALPHA == 1.3
    np.testing.assert_allclose(angstrom_beta([1.0, 3.0]), [0.00022, 0.09238])
    with pytest.raises(InvalidParameterError):
        angstrom_beta(0.9)


def test_meteorological_range_round_trip():
    t = np.array([1.0, 1.5, 2.0, 3.0, 6.0, 10.0, 30.0])
    r = meteorological_range(t)
    assert np.all(np.diff(r) < 0)
    np.testing.assert_allclose(turbidity_from_meteorological_range(r), t, rtol=1e-12)
    assert turbidity_from_meteorological_range(float(meteorological_range(4.0))) == pytest.approx(4.0)


def test_meteorological_range_against_visibility_classes():
    # T = 1 is pure air: the Koschmieder range of molecular scattering alone, 3.912 / beta_m(550) = 288 km
    # (c(T = 1) is not exactly 0, hence 280 km)
    pure = 3.912 / rayleigh_total_scattering([550.0])[0]
    assert meteorological_range(1.0) == pytest.approx(pure, rel=0.05)
    # International Visibility Code classes (McCartney 1976): measured 42 km at T = 2 (very clear, 20-50 km),
    # 15.6 km at T = 4 (clear, 10-20 km), 5.4 km at T = 10 (light haze, 4-10 km), 2.6 km at T = 20 (haze)
    assert 20e3 < meteorological_range(2.0) < 50e3
    assert 10e3 < meteorological_range(4.0) < 20e3
    assert 4e3 < meteorological_range(10.0) < 10e3
    assert 2e3 < meteorological_range(20.0) < 4e3


def test_meteorological_range_errors():
    with pytest.raises(InvalidParameterError, match="pure molecular air"):
        turbidity_from_meteorological_range(500e3)
    with pytest.raises(InvalidParameterError):
        turbidity_from_meteorological_range(-1.0)
    with pytest.raises(InvalidParameterError):
        meteorological_range(0.5)


def test_table2_daylight_basis_matches_colour_science():
    # transcription check of Table 2's S0, S1, S2 columns against an independent source
    from colour.colorimetry import SDS_BASIS_FUNCTIONS_CIE_ILLUMINANT_D_SERIES as basis

    table = load_table("preetham1999_table2")
    for name in ("S0", "S1", "S2"):
        ref = basis[name][table["wavelength_nm"]]
        np.testing.assert_allclose(table[name], ref, atol=0.051)
