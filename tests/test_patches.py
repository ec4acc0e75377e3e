"""Tregenza and Reinhart sky patches: counts, solid angles, layout, binning and patch luminance."""

import math

import numpy as np
import pytest

from skyscatter.errors import InvalidParameterError
from skyscatter.patches import SCHEMES, patch_luminance, patch_scheme
from skyscatter.photometry import patch_luminance as photometry_patch_luminance


@pytest.mark.parametrize("name,count", [("tregenza", 145), ("reinhart1", 145), ("reinhart2", 577), ("reinhart4", 2305)])
def test_counts_and_solid_angles(name, count):
    g = patch_scheme(name)
    assert g.n_patches == count
    assert np.all(g.solid_angles > 0)
    assert g.solid_angles.sum() == pytest.approx(2 * math.pi, rel=1e-13)
    assert g.centre_directions.shape == (count, 3)


def test_tregenza_layout():
    """Tregenza (1987): 12-degree bands centred at 6, 18, ..., 78 deg with 30, 30, 24, 24, 18, 12, 6 patches and a
    polar cap of 6 degrees radius."""
    g = patch_scheme("tregenza")
    counts = np.bincount(g.row)
    assert counts.tolist() == [30, 30, 24, 24, 18, 12, 6, 1]
    centres = np.degrees(g.centre_altitude)
    for r, alt in enumerate([6, 18, 30, 42, 54, 66, 78, 90]):
        np.testing.assert_allclose(centres[g.row == r], alt, atol=1e-12)
    assert g.solid_angles[-1] == pytest.approx(2 * math.pi * (1 - math.cos(math.radians(6))), rel=1e-12)
    # first patch of a band faces north, then eastwards: 12 deg steps in the horizon band
    np.testing.assert_allclose(np.degrees(g.azimuth_centre[:3]), [0, 12, 24], atol=1e-12)


def test_reinhart2_layout():
    g = patch_scheme("reinhart2")
    alpha = 90 / 14.5
    assert math.degrees(g.band_height) == pytest.approx(alpha)
    assert np.bincount(g.row).tolist() == [60, 60, 60, 60, 48, 48, 48, 48, 36, 36, 24, 24, 12, 12, 1]
    assert math.degrees(g.centre_altitude[0]) == pytest.approx(alpha / 2)
    assert math.degrees(g.azimuth_centre[1]) == pytest.approx(6.0)
    assert g.solid_angles[-1] == pytest.approx(2 * math.pi * (1 - math.cos(math.radians(alpha / 2))))


@pytest.mark.parametrize("name", sorted(set(SCHEMES)))
def test_patch_index_round_trip_and_bounds(name, rng):
    g = patch_scheme(name)
    np.testing.assert_array_equal(g.patch_index(g.centre_directions), np.arange(g.n_patches))
    v = rng.normal(size=(5000, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    idx = g.patch_index(v)
    assert np.all(idx[v[:, 2] < 0] == -1)
    up = v[:, 2] >= 0
    i, d = idx[up], v[up]
    alt = np.arcsin(d[:, 2])
    assert np.all(alt >= g.altitude_low[i] - 1e-12) and np.all(alt <= g.altitude_high[i] + 1e-12)
    az = np.mod(np.arctan2(d[:, 0], d[:, 1]), 2 * np.pi)
    dev = np.abs(np.angle(np.exp(1j * (az - g.azimuth_centre[i]))))
    assert np.all(dev <= g.azimuth_width[i] / 2 + 1e-12)


def test_sample_cells_inside_their_patch():
    g = patch_scheme("reinhart2")
    cells = g.sample_directions(3)
    assert cells.shape == (577, 9, 3)
    idx = g.patch_index(cells)
    np.testing.assert_array_equal(idx, np.repeat(np.arange(577)[:, None], 9, axis=1))


def test_patch_luminance_uniform_and_centre():
    from skyscatter.sky.base import LuminanceOnlySky

    class Sky(LuminanceOnlySky):
        def luminance(self, d):
            return 100.0 + 50.0 * np.asarray(d)[..., 2]

    np.testing.assert_allclose(patch_luminance(Sky(), "tregenza", samples=1),
                               100 + 50 * np.sin(patch_scheme("tregenza").centre_altitude))
    mean = photometry_patch_luminance(Sky(), "reinhart2", samples=4)
    g = patch_scheme("reinhart2")
    # the mean of a linear function of z = sin(alt) over an equal-area patch is its value at mid sin(alt)
    mid_u = (np.sin(g.altitude_low) + np.sin(g.altitude_high)) / 2
    np.testing.assert_allclose(mean, 100 + 50 * mid_u, rtol=1e-12)


@pytest.mark.parametrize("bad", [0, 65, 2.5, True])
def test_bad_samples(bad):
    with pytest.raises(InvalidParameterError):
        patch_scheme("tregenza").sample_directions(bad)


def test_unknown_scheme():
    with pytest.raises(InvalidParameterError, match="reinhart2"):
        patch_scheme("klems")
