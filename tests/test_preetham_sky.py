"""Preetham, Shirley & Smits 1999 sky model: Sec. 3.2 and Appendix A.2, A.5.

Expected values are computed here from the published coefficients written out independently of the
implementation (A.2; zenith chromaticity with the 5-digit published matrices, see shared/seeds/README.md).
"""

import math
import warnings

import numpy as np
import pytest

from skyscatter import PreethamSky
from skyscatter.conventions import direction_from_angles
from skyscatter.errors import InvalidDirectionError, InvalidParameterError, SunBelowHorizonError
from skyscatter.spectral import DEFAULT_WAVELENGTHS, cie_cmfs, integration_weights, xyz_to_chromaticity


def published_zenith_luminance_kcd(T, theta_s):
    # A.2: Y_z = (4.0453 T - 4.9710) tan(chi) - 0.2155 T + 2.4192, chi = (4/9 - T/120)(pi - 2 theta_s)
    chi = (4 / 9 - T / 120) * (math.pi - 2 * theta_s)
    return (4.0453 * T - 4.9710) * math.tan(chi) - 0.2155 * T + 2.4192


def published_zenith_xy(T, t):
    xz = (
        (0.00166 * t**3 - 0.00375 * t**2 + 0.00209 * t) * T * T
        + (-0.02903 * t**3 + 0.06377 * t**2 - 0.03202 * t + 0.00394) * T
        + (0.11693 * t**3 - 0.21196 * t**2 + 0.06052 * t + 0.25886)
    )
    yz = (
        (0.00275 * t**3 - 0.00610 * t**2 + 0.00317 * t) * T * T
        + (-0.04214 * t**3 + 0.08970 * t**2 - 0.04153 * t + 0.00516) * T
        + (0.15346 * t**3 - 0.26756 * t**2 + 0.06670 * t + 0.26688)
    )
    return xz, yz


def published_perez(theta, gamma, T, channel):
    table = {
        "Y": [(0.1787, -1.4630), (-0.3554, 0.4275), (-0.0227, 5.3251), (0.1206, -2.5771), (-0.0670, 0.3703)],
        "x": [(-0.0193, -0.2592), (-0.0665, 0.0008), (-0.0004, 0.2125), (-0.0641, -0.8989), (-0.0033, 0.0452)],
        "y": [(-0.0167, -0.2608), (-0.0950, 0.0092), (-0.0079, 0.2102), (-0.0441, -1.6537), (-0.0109, 0.0529)],
    }[channel]
    A, B, C, D, E = (m * T + c for m, c in table)
    return (1 + A * math.exp(B / math.cos(theta))) * (1 + C * math.exp(D * gamma) + E * math.cos(gamma) ** 2)


@pytest.mark.parametrize("T", [2.0, 3.0, 6.0])
@pytest.mark.parametrize("theta_s_deg", [0.0, 30.0, 60.0, 80.0])
def test_zenith_values_match_appendix_a2(T, theta_s_deg):
    theta_s = math.radians(theta_s_deg)
    sky = PreethamSky(T, theta_s, 0.0)
    zenith = np.array([0.0, 0.0, 1.0])
    # Exact formula reproduction: tolerance is float round-off.
    assert sky.zenith_luminance() == pytest.approx(1000 * published_zenith_luminance_kcd(T, theta_s), rel=1e-12)
    assert float(sky.luminance(zenith)) == pytest.approx(sky.zenith_luminance(), rel=1e-12)
    xz, yz = published_zenith_xy(T, theta_s)
    np.testing.assert_allclose(sky.chromaticity(zenith), [xz, yz], rtol=1e-12)


def test_zenith_luminance_sun_on_horizon():
    # A.2 with theta_s = pi/2: chi = 0, so Y_z = 2.4192 - 0.2155 T kcd/m^2 exactly.
    assert PreethamSky(2.0, math.pi / 2, 0).zenith_luminance() == pytest.approx((2.4192 - 0.431) * 1000, rel=1e-9)


@pytest.mark.parametrize("T", [2.0, 4.5, 9.0])
def test_relative_distribution_away_from_zenith(T):
    theta_s, phi_s = math.radians(40), math.radians(135)
    sky = PreethamSky(T, theta_s, phi_s)
    rng = np.random.default_rng(7)
    theta = rng.uniform(0, math.radians(88), 50)
    phi = rng.uniform(0, 2 * math.pi, 50)
    d = direction_from_angles(theta, phi)
    s = direction_from_angles(theta_s, phi_s)
    gamma = np.arccos(np.clip(d @ s, -1, 1))
    x, y = sky.chromaticity(d).T
    Y = sky.luminance(d)
    for i in range(theta.size):
        for channel, got, zen in (
            ("Y", Y[i], sky.zenith_luminance()),
            ("x", x[i], published_zenith_xy(T, theta_s)[0]),
            ("y", y[i], published_zenith_xy(T, theta_s)[1]),
        ):
            expected = zen * published_perez(theta[i], gamma[i], T, channel) / published_perez(0, theta_s, T, channel)
            assert got == pytest.approx(expected, rel=1e-10)


def test_luminance_equals_integral_of_spectral_radiance():
    # Issue requirement: luminance() = 683 * integral(L_lambda ybar) within 0.5 %, here on the coarse
    # 41-wavelength grid (the model normalises on a 5 nm grid, so this is a real check of the quadrature).
    sky = PreethamSky(3.0, math.radians(50), 1.0)
    d = direction_from_angles(np.linspace(0, 1.5, 30), np.linspace(0, 6, 30))
    L = sky.spectral_radiance(d, DEFAULT_WAVELENGTHS)
    ybar = cie_cmfs(DEFAULT_WAVELENGTHS)[:, 1] * integration_weights(DEFAULT_WAVELENGTHS)
    np.testing.assert_allclose(683 * L @ ybar, sky.luminance(d), rtol=5e-3)


def test_spectral_chromaticity_round_trip():
    sky = PreethamSky(2.5, math.radians(45), 0.3)
    d = direction_from_angles(np.linspace(0, 1.4, 12), 0.0)
    wl = np.arange(360.0, 831.0, 1.0)
    from skyscatter.spectral import spectrum_to_xyz

    xy = xyz_to_chromaticity(spectrum_to_xyz(sky.spectral_radiance(d, wl), wl))
    np.testing.assert_allclose(xy, sky.chromaticity(d), atol=1e-3)


def test_xyz_consistent_with_luminance_and_chromaticity():
    sky = PreethamSky(4.0, 0.9, 2.0)
    d = direction_from_angles(np.linspace(0, 1.5, 9), np.linspace(0, 6, 9))
    xyz = sky.xyz(d)
    np.testing.assert_allclose(xyz[..., 1], sky.luminance(d), rtol=1e-12)
    np.testing.assert_allclose(xyz_to_chromaticity(xyz), sky.chromaticity(d), rtol=1e-12)


@pytest.mark.parametrize("T", [1.65, 2.0, 5.0, 8.0, 11.0])
@pytest.mark.parametrize("theta_s_deg", [0.0, 45.0, 75.0, 90.0])
def test_properties_nonnegative_finite_symmetric(T, theta_s_deg):
    phi_s = 1.1
    sky = PreethamSky(T, math.radians(theta_s_deg), phi_s)
    theta = np.linspace(0, math.pi / 2, 25)
    dphi = np.linspace(0, math.pi, 19)
    th, dp = np.meshgrid(theta, dphi)
    left = sky.spectral_radiance(direction_from_angles(th, phi_s + dp))
    right = sky.spectral_radiance(direction_from_angles(th, phi_s - dp))
    assert np.all(np.isfinite(left)) and np.all(left >= 0)
    np.testing.assert_allclose(left, right, rtol=1e-9, atol=1e-12)
    assert np.all(sky.luminance(direction_from_angles(th, phi_s + dp)) > 0)


def test_circumsolar_brightening_and_horizon():
    sky = PreethamSky(2.5, math.radians(50), 0.0)
    near_sun = direction_from_angles(math.radians(47), 0.0)
    opposite = direction_from_angles(math.radians(47), math.pi)
    assert sky.luminance(near_sun) > 3 * sky.luminance(opposite)
    horizon = direction_from_angles(math.pi / 2, 1.0)
    assert np.isfinite(sky.luminance(horizon)) and sky.luminance(horizon) > 0


def test_below_horizon_behaviour():
    d = direction_from_angles(math.radians(100), 0.5)
    flat = direction_from_angles(math.pi / 2, 0.5)
    assert float(PreethamSky(2, 0.5, 0).luminance(d)) == 0.0
    assert np.all(PreethamSky(2, 0.5, 0).spectral_radiance(d) == 0.0)
    h = PreethamSky(2, 0.5, 0, below_horizon="horizon")
    assert float(h.luminance(d)) == pytest.approx(float(h.luminance(flat)), rel=1e-9)
    assert np.isfinite(h.luminance([0, 0, -1.0]))


@pytest.mark.parametrize("shape", [(), (5,), (2, 3), (4, 1, 2)])
def test_broadcasting_shapes(shape):
    sky = PreethamSky(3.0, 0.7, 0.2)
    d = np.broadcast_to(np.array([0.3, 0.4, 0.866]), (*shape, 3))
    assert sky.luminance(d).shape == shape
    assert sky.xyz(d).shape == (*shape, 3)
    assert sky.spectral_radiance(d, [450.0, 550.0, 650.0]).shape == (*shape, 3)


def test_float32_directions_accepted():
    sky = PreethamSky(3.0, 0.7, 0.2)
    d = np.array([[0.0, 0.0, 1.0]], dtype=np.float32)
    assert np.isfinite(sky.luminance(d)).all()


@pytest.mark.parametrize("T", [1.0, 1.6, 11.5, 25.0, float("nan")])
def test_turbidity_out_of_range_is_refused(T):
    with pytest.raises(InvalidParameterError, match="turbidity"):
        PreethamSky(T, 0.5, 0.0)


def test_non_strict_extrapolation_warns_and_never_negative():
    with pytest.warns(UserWarning, match="outside"):
        sky = PreethamSky(12.0, math.radians(89), 0.0, strict=False)
    d = direction_from_angles(np.linspace(0, math.pi / 2, 20), np.linspace(0, 6, 20))
    assert np.all(sky.luminance(d) >= 0)
    assert np.all(np.isfinite(sky.spectral_radiance(d)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(InvalidParameterError):
            PreethamSky(1.2, math.radians(30), 0.0, strict=False)  # F(0, theta_s) <= 0


def test_sun_below_horizon_refused():
    with pytest.raises(SunBelowHorizonError, match="below the horizon"):
        PreethamSky(2.0, math.radians(95), 0.0)


def test_nan_direction_refused():
    with pytest.raises(InvalidDirectionError):
        PreethamSky(2.0, 0.5, 0.0).luminance([np.nan, 0, 1])
    with pytest.raises(InvalidDirectionError):
        PreethamSky(2.0, 0.5, 0.0).luminance([0, 0])
