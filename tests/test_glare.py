"""Glare in the eye (Spencer, Shirley, Zimmerman & Greenberg 1995) and the tone mapper it feeds."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from skyscatter.errors import InvalidParameterError
from skyscatter.render.glare import (
    apply_glare,
    convolve_fft,
    glare_kernel,
    spencer_psf,
    spencer_psf_mass,
)
from skyscatter.render.tonemap import tonemap


def test_psf_components_at_published_constants():
    """The PSF at theta = 0 and 1 deg from the component formulas of Spencer et al. 1995 (Sec. 4-5)."""
    f0_0, f1_0, f2_0 = 2.61e6, 20.91 / 0.02**3, 72.37 / 0.02**2
    assert spencer_psf(0.0) == pytest.approx(0.384 * f0_0 + 0.478 * f1_0 + 0.138 * f2_0, rel=1e-12)
    at1 = 0.384 * 2.61e6 * math.exp(-((1 / 0.02) ** 2)) + 0.478 * 20.91 / 1.02**3 + 0.138 * 72.37 / 1.02**2
    assert spencer_psf(1.0) == pytest.approx(at1, rel=1e-12)
    # scotopic: what is left after the monotone parts is 0.033 f3, the lenticular halo, a ring at 3 lambda / 568
    theta = np.linspace(2.0, 4.0, 2001)
    monotone = 0.282 * 2.61e6 * np.exp(-((theta / 0.02) ** 2)) + 0.478 * 20.91 / (theta + 0.02) ** 3 \
        + 0.207 * 72.37 / (theta + 0.02) ** 2
    halo = spencer_psf(theta, adaptation="scotopic", wavelength=600.0) - monotone
    assert theta[np.argmax(halo)] == pytest.approx(3 * 600 / 568, abs=1e-3)
    assert halo.max() == pytest.approx(0.033 * 436.9 * 568 / 600, rel=1e-6)


def test_photopic_psf_decreases_and_is_positive():
    theta = np.linspace(0, 60, 5000)
    p = spencer_psf(theta)
    assert np.all(p > 0) and np.all(np.diff(p) < 0)


@pytest.mark.parametrize("adaptation", ["photopic", "scotopic"])
def test_closed_form_mass_against_quadrature(adaptation):
    for r in (0.05, 1.0, 30.0):
        pieces = [0, 0.02, 0.1, 1.0, 2.0, 4.0, r] if r > 4 else [0, min(r, 0.02), r]
        ref = sum(quad(lambda t: 2 * np.pi * t * spencer_psf(t, adaptation=adaptation), a, b, epsrel=1e-12,
                       limit=200)[0] for a, b in zip(pieces[:-1], pieces[1:], strict=False) if b > a)
        assert spencer_psf_mass(r, adaptation=adaptation) == pytest.approx(ref, rel=1e-8)


@pytest.mark.parametrize("pixel_deg", [0.008, 0.047, 0.094, 0.94])
@pytest.mark.parametrize("adaptation", ["photopic", "scotopic"])
def test_kernel_conserves_energy_to_1e3(pixel_deg, adaptation):
    """The pixel-integrated kernel sums to the closed-form PSF mass within 1e-3 (before its final rescaling)."""
    k = glare_kernel(math.radians(pixel_deg), (47, 63), adaptation=adaptation)
    assert k.discretisation_error < 1e-3
    assert k.values.sum() == pytest.approx(1.0, abs=1e-12)
    assert k.values.shape == (95, 127)
    # symmetric about both axes, peak in the centre
    np.testing.assert_allclose(k.values, k.values[::-1], rtol=1e-12)
    np.testing.assert_allclose(k.values, k.values[:, ::-1], rtol=1e-12)
    assert np.argmax(k.values) == k.values.size // 2


def test_full_convolution_conserves_energy(rng):
    img = rng.random((30, 40, 3)) * 10.0
    img[7, 9] = 1e6  # a sun
    k = glare_kernel(math.radians(0.1), (29, 39)).values
    full = convolve_fft(img, k, mode="full")
    assert full.shape == (30 + 58, 40 + 78, 3)
    np.testing.assert_allclose(full.sum(axis=(0, 1)), img.sum(axis=(0, 1)), rtol=1e-3)


def test_convolution_matches_direct_sum(rng):
    img = rng.random((9, 11))
    k = rng.random((5, 7))
    from scipy.signal import convolve2d

    np.testing.assert_allclose(convolve_fft(img, k), convolve2d(img, k, mode="same"), atol=1e-12)
    np.testing.assert_allclose(convolve_fft(img, k, mode="full"), convolve2d(img, k, mode="full"), atol=1e-12)


def test_glare_spreads_a_point_source_and_keeps_a_uniform_image_inside_uniform():
    img = np.zeros((64, 64, 3))
    img[32, 32] = 1000.0
    out = apply_glare(img, math.radians(0.1))
    assert out[32, 32, 0] < 1000.0 and out[32, 40, 0] > 0 and out[32, 60, 0] > 0
    assert out[32, 40, 0] > out[32, 50, 0] > out[32, 60, 0]
    assert out.sum() <= img.sum() * (1 + 1e-9)
    flat = apply_glare(np.ones((40, 40, 3)), math.radians(0.5))
    assert flat[20, 20, 0] < 1.0 and flat[20, 20, 0] > flat[0, 0, 0]  # light leaves through the border


def test_glare_bad_input():
    with pytest.raises(InvalidParameterError, match="adaptation"):
        apply_glare(np.ones((4, 4, 3)), 0.01, adaptation="mesopic")
    with pytest.raises(InvalidParameterError, match="NaN"):
        apply_glare(np.full((4, 4, 3), np.nan), 0.01)
    with pytest.raises(InvalidParameterError, match="pixel_angle"):
        glare_kernel(0.0, (3, 3))
    with pytest.raises(InvalidParameterError, match="max_angle"):
        glare_kernel(0.01, (3, 3), max_angle=1.0)


def test_tone_mapping_after_glare_is_monotonic(rng):
    """The documented operator maps larger luminance to larger display values (tests the lead's tonemap)."""
    y = np.sort(rng.lognormal(0, 3, 500))
    img = np.stack([y, y, y], axis=-1)[None]
    out = tonemap(img)[0, :, 1]
    assert np.all(np.diff(out) >= 0) and out[0] >= 0 and out[-1] <= 1


def test_point_source_lights_whole_row_without_truncation_circle():
    # A bright point near the left edge: with the default kernel the PSF fills the whole (2H-1) x (2W-1)
    # rectangle, so pixels farther away than min(H, W) still receive light, decreasing smoothly with distance
    # (a disc truncation left a sharp circle around the sun).
    import numpy as np

    from skyscatter.render.glare import apply_glare

    img = np.zeros((40, 120, 3))
    img[20, 5] = 1e6
    out = apply_glare(img, math.radians(0.1))[20, :, 1]
    far = out[50:]
    assert np.all(far > 0)
    assert np.all(np.diff(out[6:]) < 0)
