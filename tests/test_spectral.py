import numpy as np
import pytest

from skyscatter import spectral
from skyscatter.errors import InvalidParameterError


def test_cmfs_peak_and_range():
    c = spectral.cie_cmfs([555.0, 300.0, 900.0])
    assert c[0, 1] == pytest.approx(1.0, abs=1e-3)  # ybar(555 nm) = 1.0 (CIE 1931)
    assert np.all(c[1:] == 0)


def test_equal_energy_white_is_e():
    wl = np.arange(360.0, 831.0, 1.0)
    xyz = spectral.spectrum_to_xyz(np.ones_like(wl), wl)
    np.testing.assert_allclose(spectral.xyz_to_chromaticity(xyz), [1 / 3, 1 / 3], atol=2e-4)
    # 683 * integral(ybar) = 683 * 106.857 (CIE 1931 ybar sums to 106.857 at 1 nm)
    assert xyz[1] == pytest.approx(683 * 106.857, rel=1e-3)


@pytest.mark.parametrize("cct", [4000, 5000, 6504, 10000, 20000])
def test_daylight_round_trip(cct):
    # Issue: (x, y) -> daylight spectrum -> (x, y) within 1e-3 (CIE D-series chromaticity from colour-science).
    from colour.temperature import CCT_to_xy_CIE_D

    xy = CCT_to_xy_CIE_D(cct * 1.4388 / 1.4380)
    wl = spectral.REFERENCE_WAVELENGTHS
    s = spectral.daylight_spectrum(xy[0], xy[1], wl)
    np.testing.assert_allclose(spectral.xyz_to_chromaticity(spectral.spectrum_to_xyz(s, wl)), xy, atol=1e-3)


def test_daylight_spectrum_matches_tabulated_d65():
    # Independent data: the CIE's tabulated D65 SPD (colour-science SDS_ILLUMINANTS, CIE 15:2004 Table T.1),
    # normalised at 560 nm. The CIE table was made with M1, M2 rounded to 3 decimals: 1 % tolerance.
    import colour

    d65 = colour.SDS_ILLUMINANTS["D65"]
    wl = np.arange(380.0, 781.0, 10.0)
    table = np.interp(wl, d65.wavelengths, d65.values)
    ours = spectral.daylight_spectrum(0.31271, 0.32902, wl)
    np.testing.assert_allclose(ours / ours[18], table / table[18], rtol=1e-2)


def test_srgb_white_and_inverse():
    d65 = spectral.xyY_to_xyz(0.3127, 0.3290, 1.0)
    np.testing.assert_allclose(spectral.xyz_to_linear_srgb(d65), [1, 1, 1], atol=2e-3)
    x = np.random.default_rng(0).random((4, 3))
    np.testing.assert_allclose(spectral.linear_srgb_to_xyz(spectral.xyz_to_linear_srgb(x)), x, atol=1e-12)
    assert spectral.xyz_to_linear_srgb(x.astype(np.float32)).dtype == np.float32


def test_integration_weights_trapezoid():
    w = spectral.integration_weights([400.0, 410.0, 430.0])
    np.testing.assert_allclose(w, [5, 15, 10])
    with pytest.raises(InvalidParameterError):
        spectral.integration_weights([500.0])
    with pytest.raises(InvalidParameterError):
        spectral.spectrum_to_xyz(np.ones(3), [400.0, 500.0])


def test_bad_wavelengths():
    with pytest.raises(InvalidParameterError):
        spectral.as_wavelengths([400, np.nan])
    with pytest.raises(InvalidParameterError):
        spectral.as_wavelengths([-1.0])
