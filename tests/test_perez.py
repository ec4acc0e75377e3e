"""Perez et al. 1993 all-weather sky with the Perez et al. 1990 sky parameters and luminous efficacies."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import skyscatter
from skyscatter.atmosphere.tables import load_table
from skyscatter.conventions import direction_from_angles
from skyscatter.errors import InvalidParameterError, SunBelowHorizonError
from skyscatter.sky.perez import (
    EPSILON_CAP,
    MIN_SUN_ZENITH,
    PerezSky,
    epsilon_bin,
    luminous_efficacy,
    perez_coefficients,
    perez_relative_luminance,
    precipitable_water,
    sky_brightness,
    sky_clearness,
)

# Perez et al. 1993, Table 1, typed again from the coeff_perez array of Radiance's gendaylit.c (an independent
# transcription): per bin a1-a4, b1-b4, c1-c4, d1-d4, e1-e4.
TABLE1 = [
    [1.3525, -0.2576, -0.2690, -1.4366, -0.7670, 0.0007, 1.2734, -0.1233, 2.8000, 0.6004, 1.2375, 1.000,
     1.8734, 0.6297, 0.9738, 0.2809, 0.0356, -0.1246, -0.5718, 0.9938],
    [-1.2219, -0.7730, 1.4148, 1.1016, -0.2054, 0.0367, -3.9128, 0.9156, 6.9750, 0.1774, 6.4477, -0.1239,
     -1.5798, -0.5081, -1.7812, 0.1080, 0.2624, 0.0672, -0.2190, -0.4285],
    [-1.1000, -0.2515, 0.8952, 0.0156, 0.2782, -0.1812, -4.5000, 1.1766, 24.7219, -13.0812, -37.7000, 34.8438,
     -5.0000, 1.5218, 3.9229, -2.6204, -0.0156, 0.1597, 0.4199, -0.5562],
    [-0.5484, -0.6654, -0.2672, 0.7117, 0.7234, -0.6219, -5.6812, 2.6297, 33.3389, -18.3000, -62.2500, 52.0781,
     -3.5000, 0.0016, 1.1477, 0.1062, 0.4659, -0.3296, -0.0876, -0.0329],
    [-0.6000, -0.3566, -2.5000, 2.3250, 0.2937, 0.0496, -5.6812, 1.8415, 21.0000, -4.7656, -21.5906, 7.2492,
     -3.5000, -0.1554, 1.4062, 0.3988, 0.0032, 0.0766, -0.0656, -0.1294],
    [-1.0156, -0.3670, 1.0078, 1.4051, 0.2875, -0.5328, -3.8500, 3.3750, 14.0000, -0.9999, -7.1406, 7.5469,
     -3.4000, -0.1078, -1.0750, 1.5702, -0.0672, 0.4016, 0.3017, -0.4844],
    [-1.0000, 0.0211, 0.5025, -0.5119, -0.3000, 0.1922, 0.7023, -1.6317, 19.0000, -5.0000, 1.2438, -1.9094,
     -4.0000, 0.0250, 0.3844, 0.2656, 1.0468, -0.3788, -2.4517, 1.4656],
    [-1.0500, 0.0289, 0.4260, 0.3590, -0.3250, 0.1156, 0.7781, 0.0025, 31.0625, -14.5000, -46.1148, 55.3750,
     -7.2312, 0.4050, 13.3500, 0.6234, 1.5000, -0.6426, 1.8564, 0.5636],
]
# Perez et al. 1990, Table 4, typed from Radiance's gendaylit.c: (a, b, c, d) for global, direct, diffuse.
TABLE4 = {
    "global": [(96.63, -0.47, 11.50, -9.16), (107.54, 0.79, 1.79, -1.19), (98.73, 0.70, 4.40, -6.95),
               (92.72, 0.56, 8.36, -8.31), (86.73, 0.98, 7.10, -10.94), (88.34, 1.39, 6.06, -7.60),
               (78.63, 1.47, 4.93, -11.37), (99.65, 1.86, -4.46, -3.15)],
    "direct": [(57.20, -4.55, -2.98, 117.12), (98.99, -3.46, -1.21, 12.38), (109.83, -4.90, -1.71, -8.81),
               (110.34, -5.84, -1.99, -4.56), (106.36, -3.97, -1.75, -6.16), (107.19, -1.25, -1.51, -26.73),
               (105.75, 0.77, -1.26, -34.44), (101.18, 1.58, -1.10, -8.29)],
    "diffuse": [(97.24, -0.46, 12.00, -8.91), (107.22, 1.15, 0.59, -3.95), (104.97, 2.96, -5.53, -8.77),
                (102.39, 5.59, -13.95, -13.90), (100.71, 5.94, -22.75, -23.74), (106.42, 3.83, -36.15, -28.83),
                (141.88, 1.90, -53.24, -14.03), (152.23, 0.35, -45.27, -7.98)],
}
BIN_CENTRES = [1.03, 1.15, 1.4, 1.7, 2.4, 3.5, 5.3, 9.0]


def test_exported():
    assert skyscatter.PerezSky is PerezSky


def test_coefficient_table_reproduced():
    table = load_table("perez1993_coefficients")
    cols = [f"{k}{j}" for k in "abcde" for j in range(1, 5)]
    for b in range(8):
        assert [table[c][b] for c in cols] == pytest.approx(TABLE1[b], abs=0)


def test_efficacy_table_reproduced():
    table = load_table("perez1990_luminous_efficacy")
    for kind, rows in TABLE4.items():
        for b, row in enumerate(rows):
            assert [table[f"{kind}_{k}"][b] for k in "abcd"] == pytest.approx(row, abs=0)


@pytest.mark.parametrize("b", range(1, 8))
def test_coefficients_per_bin_eq6(b):
    """Bins 2-8: X = X1 + X2 Z + delta (X3 + X4 Z) with the table row (Eq. 6); delta 0.3 avoids the floor."""
    eps, delta, z = BIN_CENTRES[b], 0.3, 0.6
    row = np.array(TABLE1[b]).reshape(5, 4)
    expected = row[:, 0] + row[:, 1] * z + delta * (row[:, 2] + row[:, 3] * z)
    np.testing.assert_allclose(perez_coefficients(eps, delta, z), expected, rtol=1e-13)


def test_bin1_special_forms_eqs7_8():
    eps, delta, z = 1.02, 0.15, 0.8
    c1, c2, c3, c4 = TABLE1[0][8:12]
    d1, d2, d3, d4 = TABLE1[0][12:16]
    k = perez_coefficients(eps, delta, z)
    assert k[2] == pytest.approx(math.exp((delta * (c1 + c2 * z)) ** c3) - c4, rel=1e-13)
    assert k[3] == pytest.approx(-math.exp(delta * (d1 + d2 * z)) + d3 + delta * d4, rel=1e-13)
    a1, a2, a3, a4 = TABLE1[0][0:4]
    assert k[0] == pytest.approx(a1 + a2 * z + delta * (a3 + a4 * z), rel=1e-13)


def test_epsilon_bins():
    edges = [1.0, 1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200]
    np.testing.assert_array_equal(epsilon_bin(edges), np.arange(8))
    np.testing.assert_array_equal(epsilon_bin(np.array(edges[1:]) - 1e-9), np.arange(7))
    assert epsilon_bin(50.0) == 7


def test_sky_parameters_by_hand():
    """Perez 1990 Eqs. 1-3 for D_h = 120, I_n = 700 W m^-2, Z = 30 deg, day 172, T_d = 15 deg C."""
    z = math.radians(30)
    k = 1.041 * z**3
    assert float(sky_clearness(700.0, 120.0, z)) == pytest.approx((820 / 120 + k) / (1 + k), rel=1e-13)
    m = 1 / (math.cos(z) + 0.15 * (93.885 - 30) ** -1.253)  # Kasten 1966
    b = 2 * math.pi * (172 - 1) / 365
    e0 = (1.00011 + 0.034221 * math.cos(b) + 0.00128 * math.sin(b) + 0.000719 * math.cos(2 * b)
          + 0.000077 * math.sin(2 * b))
    assert float(sky_brightness(120.0, z, 172)) == pytest.approx(120 * m / (1367 * e0), rel=1e-9)
    assert float(precipitable_water(15.0)) == pytest.approx(math.exp(0.07 * 15 - 0.075), rel=1e-13)
    w = 2.0
    assert float(luminous_efficacy("diffuse", 6.1, 0.1, z, w)) == pytest.approx(
        141.88 + 1.90 * w - 53.24 * math.cos(z) - 14.03 * math.log(0.1), rel=1e-13)
    assert float(luminous_efficacy("direct", 6.1, 0.1, z, w)) == pytest.approx(
        105.75 + 0.77 * w - 1.26 * math.exp(5.73 * z - 5) - 34.44 * 0.1, rel=1e-13)
    assert float(luminous_efficacy("global", 1.01, 0.2, z, w)) == pytest.approx(
        96.63 - 0.47 * w + 11.50 * math.cos(z) - 9.16 * math.log(0.2), rel=1e-13)


def test_irradiance_and_parameter_routes_agree():
    """(I_n, D_h) -> (epsilon, delta) -> sky equals the sky built from (I_n, D_h) directly (Eqs. 1-2 inverted)."""
    z, doy = math.radians(40), 100
    a = PerezSky(z, 2.0, direct_normal_irradiance=600.0, diffuse_horizontal_irradiance=150.0, day_of_year=doy,
                 dew_point=8.0)
    b = PerezSky(z, 2.0, epsilon=a.epsilon, delta=a.delta, day_of_year=doy, dew_point=8.0)
    assert b.diffuse_horizontal_irradiance == pytest.approx(150.0, rel=1e-12)
    assert b.direct_normal_irradiance == pytest.approx(600.0, rel=1e-12)
    assert b.diffuse_illuminance == pytest.approx(a.diffuse_illuminance, rel=1e-12)
    assert b.sun_illuminance_normal == pytest.approx(a.sun_illuminance_normal, rel=1e-12)
    c = PerezSky(z, 2.0, epsilon=a.epsilon, delta=a.delta, diffuse_illuminance=a.diffuse_illuminance, dew_point=8.0)
    assert c.sun_illuminance_normal == pytest.approx(a.sun_illuminance_normal, rel=1e-12)


@pytest.mark.parametrize("eps,delta", [(1.0, 0.1), (1.4, 0.3), (3.5, 0.2), (9.0, 0.12)])
def test_normalised_to_diffuse_illuminance_by_independent_quadrature(eps, delta):
    """A fine equal-area midpoint rule in (cos theta, phi), not the library's Gauss rule, integrates to D_v."""
    sky = PerezSky(math.radians(35), 1.0, epsilon=eps, delta=delta, diffuse_illuminance=20_000.0)
    n_u, n_phi = 1200, 2400
    u = (np.arange(n_u) + 0.5) / n_u  # cos(theta)
    phi = 2 * np.pi * (np.arange(n_phi) + 0.5) / n_phi
    total = 0.0
    for rows in np.array_split(np.arange(n_u), 8):
        d = direction_from_angles(np.arccos(u[rows])[:, None], phi[None, :])
        total += float((sky.luminance(d) * u[rows][:, None]).sum())
    value = total * (1.0 / n_u) * (2 * np.pi / n_phi)
    assert value == pytest.approx(20_000.0, rel=1e-4)


@settings(max_examples=40, deadline=None)
@given(
    eps=st.floats(1.0, 12.0),
    delta=st.floats(0.01, 0.6),
    sun_zenith=st.floats(0.0, math.radians(89.0)),
    sun_azimuth=st.floats(0.0, 2 * math.pi),
    zenith=st.floats(0.0, math.pi / 2),
    offset=st.floats(0.0, math.pi),
)
def test_symmetric_non_negative_finite(eps, delta, sun_zenith, sun_azimuth, zenith, offset):
    sky = PerezSky(sun_zenith, sun_azimuth, epsilon=eps, delta=delta, diffuse_illuminance=10_000.0)
    d = direction_from_angles(zenith, np.array([sun_azimuth + offset, sun_azimuth - offset]))
    lum = sky.luminance(d)
    assert np.all(np.isfinite(lum)) and np.all(lum >= 0)
    assert lum[0] == pytest.approx(lum[1], rel=1e-9, abs=1e-9)


def test_below_horizon_zero_and_horizon_finite():
    sky = PerezSky(0.6, 0.0, epsilon=8.0, delta=0.2)
    az = np.linspace(0, 2 * np.pi, 9)
    assert np.all(sky.luminance(direction_from_angles(2.0, az)) == 0)
    h = sky.luminance(direction_from_angles(math.pi / 2, az))
    assert np.all(np.isfinite(h)) and np.all(h >= 0)


# -- the guards ---------------------------------------------------------------------------------------------------


def test_guard_epsilon_cap():
    sky = PerezSky(0.5, 0.0, epsilon=25.0, delta=0.1)
    assert sky.epsilon == EPSILON_CAP and any("capped" in n for n in sky.guards_applied)
    raw = PerezSky(0.5, 0.0, epsilon=25.0, delta=0.1, guards=False)
    assert raw.epsilon == 25.0 and raw.epsilon_bin == 8


def test_guard_delta_range():
    assert PerezSky(0.5, 0.0, epsilon=8.0, delta=0.001).delta == 0.01
    assert PerezSky(0.5, 0.0, epsilon=8.0, delta=0.9).delta == 0.6
    assert PerezSky(0.5, 0.0, epsilon=1.02, delta=0.65, guards=False).delta == 0.65


def test_guard_delta_floor_in_bins_2_to_5():
    sky = PerezSky(0.5, 0.0, epsilon=2.0, delta=0.05)
    np.testing.assert_allclose(list(sky.coefficients.values()), perez_coefficients(2.0, 0.2, 0.5, delta_floor=False))
    assert sky.coefficients["b"] < 0
    raw = perez_coefficients(2.0, 0.05, 0.5, delta_floor=False)
    assert raw[1] > 0  # why the floor exists: exp(b / cos theta) then diverges at the horizon
    near_horizon = math.cos(math.radians(89.99))
    # Under the one horizon rule (cos theta floored at 0.01, Radiance perezlum.cal) the raw form stays finite but is
    # far out of scale: (1 + a e^(b/0.01)) (1 + c e^(d gamma) + e cos^2 gamma) = -1.1e4 for these coefficients.
    a, b, c, d, e = raw
    expected = (1 + a * math.exp(b / 0.01)) * (1 + c * math.exp(d * 0.5) + e * math.cos(0.5) ** 2)
    assert expected < -1e4
    assert float(perez_relative_luminance(near_horizon, math.cos(0.5), raw, guards=False)) == pytest.approx(expected)
    guarded = sky.relative_luminance(direction_from_angles(math.radians(89.99), math.pi))
    assert 0 <= float(guarded) < 10
    assert not (perez_coefficients(1.02, 0.05, 0.5) == perez_coefficients(1.02, 0.2, 0.5)).all()  # bin 1: no floor


def test_guard_sun_altitude_clamp():
    sky = PerezSky(0.0, 1.0, epsilon=6.0, delta=0.2)
    assert sky.model_sun_zenith == pytest.approx(MIN_SUN_ZENITH)
    np.testing.assert_allclose(list(sky.coefficients.values()), perez_coefficients(6.0, 0.2, MIN_SUN_ZENITH))
    assert math.isfinite(sky.zenith_luminance)
    raw = PerezSky(0.0, 1.0, epsilon=6.0, delta=0.2, guards=False)
    assert raw.model_sun_zenith == 0.0


def test_guard_negative_luminance_clamped():
    # bin 4 with a large delta: c < 0, so 1 + c exp(d gamma) < 0 around the sun
    z = math.radians(3.0)
    raw = PerezSky(z, 0.0, epsilon=1.7, delta=0.6, guards=False)
    sky = PerezSky(z, 0.0, epsilon=1.7, delta=0.6)
    assert raw.coefficients["c"] < 0
    d = direction_from_angles(np.linspace(0, 1.5, 40), 0.0)
    assert np.any(raw.relative_luminance(d) < 0)
    rel = sky.relative_luminance(d)
    assert np.all(rel >= 0)
    np.testing.assert_allclose(rel, np.maximum(raw.relative_luminance(d), 0.0), rtol=1e-12)


def test_guard_uniform_fallback():
    sky = PerezSky(0.05, 0.0, epsilon=3.5, delta=0.01)
    assert sky.uniform and any("uniform" in n for n in sky.guards_applied)
    assert sky.zenith_luminance == pytest.approx(sky.diffuse_illuminance / math.pi, rel=1e-12)


def test_extraterrestrial_irradiance_equals_pvlib_spencer():
    """Spencer (1971) eccentricity factor times 1367 W m^-2, against pvlib's implementation of the same series."""
    from pvlib.irradiance import get_extra_radiation

    from skyscatter.sky.perez import extraterrestrial_irradiance

    doy = np.arange(1, 367)
    ref = np.asarray(get_extra_radiation(doy.astype(float), solar_constant=1367.0, method="spencer"))
    np.testing.assert_allclose(extraterrestrial_irradiance(doy), ref, rtol=1e-15)
    # perihelion in early January at 0.98329 AU: (1 / 0.98329)^2 = 1.0343; Spencer's fit gives 1.0351 there
    assert extraterrestrial_irradiance(3) == pytest.approx(1367.0 / 0.98329**2, rel=1e-3)
    assert extraterrestrial_irradiance(None) == 1367.0


def test_horizon_cos_floor():
    k = np.array([0.5, 0.1, 0.0, 0.0, 0.0])
    assert float(perez_relative_luminance(0.0, 0.0, k)) == pytest.approx(1 + 0.5 * math.exp(0.1 / 0.01))


@pytest.mark.parametrize(
    "kwargs,err",
    [
        ({"epsilon": 2.0}, InvalidParameterError),
        ({"direct_normal_irradiance": 1415.0, "diffuse_horizontal_irradiance": 50.0}, InvalidParameterError),
        ({"direct_normal_irradiance": 500.0, "diffuse_horizontal_irradiance": 1e6}, InvalidParameterError),
        ({"epsilon": 2.0, "delta": 0.1, "diffuse_illuminance": 1e308}, InvalidParameterError),
        ({"epsilon": 0.9, "delta": 0.1}, InvalidParameterError),
        ({"epsilon": 2.0, "delta": -0.1}, InvalidParameterError),
        ({"epsilon": 2.0, "delta": 0.1, "direct_normal_irradiance": 100.0}, InvalidParameterError),
        ({"direct_normal_irradiance": 100.0}, InvalidParameterError),
        ({"direct_normal_irradiance": -1.0, "diffuse_horizontal_irradiance": 50.0}, InvalidParameterError),
        ({"direct_normal_irradiance": 100.0, "diffuse_horizontal_irradiance": 0.0}, InvalidParameterError),
        ({"epsilon": 2.0, "delta": 0.1, "day_of_year": 0}, InvalidParameterError),
        ({"epsilon": 2.0, "delta": 0.1, "day_of_year": 10.5}, InvalidParameterError),
        ({"epsilon": 2.0, "delta": 0.1, "diffuse_illuminance": -5.0}, InvalidParameterError),
        ({"epsilon": float("nan"), "delta": 0.1}, InvalidParameterError),
        ({"epsilon": 2.0, "delta": 0.1, "sun_zenith": 1.8}, SunBelowHorizonError),
    ],
)
def test_bad_input(kwargs, err):
    kw = dict(kwargs)
    zen = kw.pop("sun_zenith", 0.5)
    with pytest.raises(err):
        PerezSky(zen, 0.0, **kw)


def test_sun_disc_carries_direct_illuminance():
    sky = PerezSky(0.7, 1.0, direct_normal_irradiance=750.0, diffuse_horizontal_irradiance=110.0)
    assert sky.sun_xyz()[1] * sky.sun_solid_angle == pytest.approx(sky.sun_illuminance_normal, rel=1e-10)
    assert 80 < sky.sun_illuminance_normal / 750.0 < 110  # direct efficacy of a clear sky, lm/W


def test_delta_zero_raises_no_numpy_warnings():
    import warnings

    from skyscatter import PerezSky

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sky = PerezSky(0.8, 1.0, epsilon=3.0, delta=0.0)
    assert sky.guards_applied


def test_default_sky_condition_is_a_documented_clear_sky():
    """With no sky condition the registry's "defaults" contract needs a sky: epsilon 6.5, delta 0.15 (bin 8)."""
    from skyscatter.sky.perez import DEFAULT_DELTA, DEFAULT_EPSILON

    sky = PerezSky(0.5, 0.0)
    assert (sky.epsilon, sky.delta, sky.epsilon_bin) == (DEFAULT_EPSILON, DEFAULT_DELTA, 8)
    same = PerezSky(0.5, 0.0, epsilon=6.5, delta=0.15)
    assert sky.coefficients == same.coefficients
