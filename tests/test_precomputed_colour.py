"""Colour of the 3-wavelength tables: the rho = L / E_sun reconstruction and its negative-lobe guard."""

import numpy as np

from skyscatter.precomputed import AtmosphereParameters
from skyscatter.precomputed.conversion import ColourConversion
from skyscatter.spectral import spectrum_to_xyz

TW = np.array([680.0, 550.0, 440.0])
FINE = np.arange(360.0, 831.0, 1.0)


def samples(params, rho):
    return params.solar_irradiance_at(TW) * rho(TW)


def test_quadratic_rho_reproduced_exactly():
    # A rho that is exactly quadratic in x = (lambda / 550)^-4 and positive on 360-830 nm: the reconstruction
    # is exact, so XYZ equals the observer integral of E_sun * rho computed here independently.
    params = AtmosphereParameters()
    conv = ColourConversion(TW, params)

    def rho(wl):
        x = (np.asarray(wl) / 550.0) ** -4
        return 0.02 + 0.05 * x + 0.01 * x * x

    expected = spectrum_to_xyz(params.solar_irradiance_at(FINE) * rho(FINE), FINE)
    np.testing.assert_allclose(conv.to_xyz(samples(params, rho)), expected, rtol=1e-9)


def test_sunset_samples_never_give_negative_colour_or_violet_peak():
    # Near a setting sun rho rises steeply towards the red; the quadratic through the three samples dips
    # below zero and invented a violet peak before the guard.
    params = AtmosphereParameters()
    conv = ColourConversion(TW, params)
    rad = params.solar_irradiance_at(TW) * np.array([1.0, 0.2, 0.001])
    xyz = conv.to_xyz(rad)
    assert np.all(xyz >= 0)
    spec = conv.resample(rad, np.arange(380.0, 781.0, 10.0))
    assert np.all(spec >= 0)
    ratio = spec / params.solar_irradiance_at(np.arange(380.0, 781.0, 10.0))
    assert ratio[:6].max() <= 0.001 + 1e-12  # no more blue than the 440 nm sample below 440 nm
    # the guarded rule is used only where needed: a daylight-like triple keeps the polynomial
    day = params.solar_irradiance_at(TW) * (TW / 550.0) ** -4
    np.testing.assert_allclose(conv.to_xyz(day), day @ conv.xyz_polynomial.T, rtol=1e-12)


def test_batches_mix_rules_per_sample():
    params = AtmosphereParameters()
    conv = ColourConversion(TW, params)
    day = params.solar_irradiance_at(TW) * (TW / 550.0) ** -4
    dusk = params.solar_irradiance_at(TW) * np.array([1.0, 0.2, 0.001])
    both = conv.to_xyz(np.stack([day, dusk]))
    np.testing.assert_allclose(both[0], conv.to_xyz(day))
    np.testing.assert_allclose(both[1], conv.to_xyz(dusk))


def test_spectral_mode_reproduces_rho_linear_in_wavelength_and_nothing_outside():
    # Spectral mode (16 wavelengths, 400-700 nm): rho = L / E_sun linear in lambda is reproduced exactly between
    # the samples, and nothing is added outside 400-700 nm, so XYZ equals the observer integral of E_sun * rho
    # over 400-700 nm only, computed here on the 1 nm grid with spectrum_to_xyz.
    params = AtmosphereParameters()
    tw = np.arange(400.0, 701.0, 20.0)
    conv = ColourConversion(tw, params)
    assert conv.spectral and not conv.guarded

    def rho(wl):
        return 0.3 - 0.0003 * (np.asarray(wl) - 400.0)

    rad = params.solar_irradiance_at(tw) * rho(tw)
    inside = FINE[(FINE >= 400.0) & (FINE <= 700.0)]
    expected = spectrum_to_xyz(params.solar_irradiance_at(inside) * rho(inside), inside)
    np.testing.assert_allclose(conv.to_xyz(rad), expected, rtol=1e-9)
    spec = conv.resample(rad, [390.0, 400.0, 455.0, 700.0, 710.0])
    at = np.array([400.0, 455.0, 700.0])
    np.testing.assert_allclose(spec[1:4], params.solar_irradiance_at(at) * rho(at), rtol=1e-12)
    assert spec[0] == 0.0 and spec[4] == 0.0
