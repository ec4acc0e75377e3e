"""The rendering lookups' read of the multiple scattering along the view-sun azimuth: four azimuth texels, the
four-point Lagrange rule where they are smooth, the log-linear read of the cell where they fall steeply
(:func:`skyscatter.precomputed.geometry.azimuth_four_point`, ``azimuth_read_weights``,
:func:`skyscatter.precomputed.sampling.lookup4_cell_azimuth`; docs/accuracy.md, "Low sun").

Published values: Abramowitz & Stegun (1964) Eq. 25.2.13, the four-point Lagrange weights at p = 1/2:
-1/16, 9/16, 9/16, -1/16. The read's effect on the sky is held by tests/test_precomputed_low_sun.py (the stored
Monte Carlo)."""

import math

import numpy as np
import pytest

from skyscatter.precomputed.geometry import (
    AZIMUTH_RATIO_FOUR_POINT,
    AZIMUTH_RATIO_LOG_LINEAR,
    azimuth_four_point,
    azimuth_read_weights,
    log_lerp_weight,
)
from skyscatter.precomputed.sampling import (
    TEXEL_SNAP,
    lookup4_cell,
    lookup4_cell_azimuth,
    lookup4_cell_azimuth_each,
    snap_to_texel,
)


def _read(values, i_n, w):
    """The read of ``values`` (one per azimuth texel, > 0) at the fraction ``w`` of the cell ``i_n``."""
    j0, j3, l0, l1, l2, l3 = azimuth_four_point(i_n, w, len(values))
    taps = (j0, i_n, i_n + 1, j3)
    weights = azimuth_read_weights(*(values[j] for j in taps), w, l0, l1, l2, l3)
    return sum(wt * values[j] for wt, j in zip(weights, taps, strict=True)), weights


def test_four_point_weights_are_the_published_ones():
    """A&S 25.2.13 at the cell's middle: -1/16, 9/16, 9/16, -1/16; at its ends the texels themselves."""
    _, _, *lw = azimuth_four_point(3, 0.5, 8)
    np.testing.assert_allclose(lw, [-1 / 16, 9 / 16, 9 / 16, -1 / 16], rtol=0, atol=1e-15)
    for w, want in ((0.0, [0, 1, 0, 0]), (1.0, [0, 0, 1, 0])):
        _, _, *lw = azimuth_four_point(3, w, 8)
        np.testing.assert_allclose(lw, want, rtol=0, atol=1e-15)
    for w in np.linspace(0.0, 1.0, 11):
        assert sum(azimuth_four_point(2, float(w), 8)[2:]) == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize(("i_n", "n", "taps"), [(0, 8, (1, 2)), (1, 8, (0, 3)), (5, 8, (4, 7)), (6, 8, (5, 6)),
                                                (0, 2, (1, 0)), (0, 3, (1, 2)), (1, 3, (0, 1))])
def test_outer_texels_are_mirrored_at_the_axis_ends(i_n, n, taps):
    """The texel before the first is the second, the one after the last the one before it (the view-sun azimuth
    from 0 to pi: the sky is symmetric about both ends)."""
    assert azimuth_four_point(i_n, 0.3, n)[:2] == taps


def test_smooth_values_are_read_exactly_for_a_cubic():
    """Values within the four-point bound: the read of a cubic in the texel index is the cubic (interior cells),
    and of a quadratic even about an end is that quadratic in the end cells (the mirrored taps)."""
    x = np.arange(8.0)
    cubic = 3.0 + 0.05 * (x - 2.0) + 0.02 * (x - 3.5) ** 2 - 0.002 * (x - 3.0) ** 3  # within a factor 2
    assert cubic.max() / cubic.min() < AZIMUTH_RATIO_FOUR_POINT
    for i_n in range(1, 6):
        for w in (0.1, 0.5, 0.77):
            got, _ = _read(cubic, i_n, w)
            t = i_n + w
            want = 3.0 + 0.05 * (t - 2.0) + 0.02 * (t - 3.5) ** 2 - 0.002 * (t - 3.0) ** 3
            assert got == pytest.approx(want, rel=1e-12)
    for end, i_n, w in ((0.0, 0, 0.4), (7.0, 6, 0.6)):  # quadratics even about the first and the last texel
        even = 2.0 + 0.3 * (x - end) ** 2 / 49.0
        got, _ = _read(even, i_n, w)
        assert got == pytest.approx(2.0 + 0.3 * (i_n + w - end) ** 2 / 49.0, rel=1e-12)


def test_a_steep_fall_is_read_log_linearly():
    """A fall of 10x per texel (the Earth's shadow in twilight): the four-point rule would undershoot below zero
    (100, 10, 1, 0.1 -> -0.07 half way between 10 and 1); beyond the log-linear bound the read is the cell's
    log-linear one, the geometric mean at the middle."""
    values = np.array([1000.0, 100.0, 10.0, 1.0, 0.1, 0.01, 0.001, 0.0001])
    four = sum(c * v for c, v in zip((-1 / 16, 9 / 16, 9 / 16, -1 / 16), values[1:5], strict=True))
    assert four < 0.0
    got, weights = _read(values, 2, 0.5)
    assert weights[0] == 0.0 and weights[3] == 0.0
    g = log_lerp_weight(10.0, 1.0, 0.5)
    assert weights[2] == pytest.approx(g, rel=1e-15)
    assert got == pytest.approx(math.sqrt(10.0), rel=1e-12)

    # smooth values but one texel at zero (below the tables' sun limit, deep in the shadow): the log-linear read,
    # finite; all four at zero: finite weights, the linear ones (log_lerp_weight of two zeros is w)
    smooth = np.ones(8)
    smooth[4] = 0.0
    got, weights = _read(smooth, 2, 0.3)  # taps 1, 2, 3, 4
    assert np.all(np.isfinite(weights)) and weights[0] == 0.0 and weights[3] == 0.0
    assert weights[2] == pytest.approx(log_lerp_weight(1.0, 1.0, 0.3), rel=1e-15) and got == pytest.approx(1.0)
    got, weights = _read(np.zeros(8), 3, 0.3)
    np.testing.assert_allclose(weights, [0.0, 0.7, 0.3, 0.0], rtol=0, atol=1e-15)
    assert got == 0.0


def test_the_read_is_continuous_between_the_two_rules():
    """Between the two bounds the weights blend linearly in the ratio of the largest to the smallest value:
    continuous as the values steepen, the four-point weights at the lower bound, the log-linear at the upper."""
    base = np.array([1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    reads = []
    for q in np.linspace(1.5, 5.0, 141):
        v = base.copy()
        v[4] = q  # the texel after the cell (2, 3): the ratio of the four is q
        reads.append(_read(v, 2, 0.5)[0])
    steps = np.abs(np.diff(reads))
    assert steps.max() < 0.02
    v = base.copy()
    v[4] = AZIMUTH_RATIO_FOUR_POINT
    np.testing.assert_allclose(np.array(_read(v, 2, 0.5)[1])[[0, 3]], [-1 / 16, -1 / 16], rtol=1e-12)
    v[4] = AZIMUTH_RATIO_LOG_LINEAR
    np.testing.assert_allclose(np.array(_read(v, 2, 0.5)[1])[[0, 3]], [0.0, 0.0], atol=1e-15)


def test_the_table_read_matches_the_rule():
    """:func:`lookup4_cell_azimuth` on a 4D table: each azimuth texel's column interpolated in r, mu and mu_s, the
    weights of the rule from the middle wavelength applied to every wavelength (one set of weights: the read is
    linear in the table, so it folds into colour; the observer slices' path against the 4D lookup is
    ``tests/test_precomputed_sky.py``); with the values steep it is the two-texel :func:`lookup4_cell`."""
    rng = np.random.default_rng(3)
    shape = (3, 4, 3, 8, 5)
    # within 10 % along nu (the four-point regime), each wavelength a multiple of the middle one's
    table = ((1.0 + 0.1 * rng.random(shape[:4]))[..., None] * np.array([1.0, 1.3, 1.7, 2.0, 2.2])).astype(np.float32)
    cell = (1, 0.3, 1, 0.6, 2, 0.25, 1, 0.4)  # i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s
    for i_n, w in ((0, 0.35), (3, 0.5), (6, 0.8)):
        out = np.zeros(5)
        lookup4_cell_azimuth(table, *cell, i_n, w, 1.0, out)
        # the same read by hand: each azimuth texel's column interpolated in r, mu, mu_s, then the rule
        cols = np.zeros((8, 5))
        i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s = cell
        for a, wa in ((0, 1 - w_r), (1, w_r)):
            i_mu, w_mu = (i_mu1, w_mu1) if a else (i_mu0, w_mu0)
            for b, wb in ((0, 1 - w_mu), (1, w_mu)):
                for c, wc in ((0, 1 - w_s), (1, w_s)):
                    cols += wa * wb * wc * table[i_r + a, i_mu + b, i_s + c]
        j0, j3, l0, l1, l2, l3 = azimuth_four_point(i_n, w, 8)
        taps = (j0, i_n, i_n + 1, j3)
        weights = azimuth_read_weights(*(cols[j, 2] for j in taps), w, l0, l1, l2, l3)
        want = sum(wt * cols[j] for wt, j in zip(weights, taps, strict=True))
        np.testing.assert_allclose(out, want, rtol=2e-6)
        assert weights[0] != 0.0  # the four-point rule, not the fall-back
    steep = table.copy()
    steep[..., :] *= (10.0 ** -np.arange(8.0))[None, None, None, :, None]
    out4 = np.zeros(5)
    out2 = np.zeros(5)
    lookup4_cell_azimuth(steep, *cell, 3, 0.5, 1.0, out4)
    lookup4_cell(steep, *cell, 3, 0.5, 1.0, out2)
    np.testing.assert_allclose(out4, out2, rtol=1e-6)


@pytest.mark.parametrize("cell", [
    (1, 0.3, 1, 0.6, 2, 0.25, 1, 0.4),  # inside every cell
    (1, 0.0, 1, 0.6, 2, 0.25, 1, 0.0),  # at a radius and a sun-zenith texel: the scattering density's reads
    (0, 1.0, 1, 0.6, 2, 0.25, 1, 1.0),  # the same texels from the cell below
])
def test_the_precomputations_read_has_each_wavelengths_own_weights(cell):
    """:func:`lookup4_cell_azimuth_each` (the scattering density's read of the previous order) against the rule by
    hand at every wavelength: each azimuth texel's column interpolated in r, mu and mu_s, the rule's weights from
    that wavelength's own four values, so that a wavelength's value does not depend on the others (the tables do
    not depend on the wavelength chunking); corners of zero weight are skipped without changing the value."""
    rng = np.random.default_rng(5)
    shape = (3, 4, 3, 8, 5)
    # smooth at some wavelengths, steep at others: both rules of the read
    table = (1.0 + 0.1 * rng.random(shape)).astype(np.float32)
    table[..., 3:] *= (10.0 ** -np.arange(8.0))[:, None].astype(np.float32)
    i_r, w_r, i_mu0, w_mu0, i_mu1, w_mu1, i_s, w_s = cell
    for i_n, w in ((0, 0.35), (3, 0.5), (6, 0.8)):
        out = np.zeros(5)
        lookup4_cell_azimuth_each(table, *cell, i_n, w, 2.0, out, np.empty((4, 5)))
        cols = np.zeros((8, 5))
        for a, wa in ((0, 1 - w_r), (1, w_r)):
            i_mu, w_mu = (i_mu1, w_mu1) if a else (i_mu0, w_mu0)
            for b, wb in ((0, 1 - w_mu), (1, w_mu)):
                for c, wc in ((0, 1 - w_s), (1, w_s)):
                    if wa * wb * wc:
                        cols += wa * wb * wc * table[i_r + a, i_mu + b, i_s + c]
        j0, j3, l0, l1, l2, l3 = azimuth_four_point(i_n, w, 8)
        taps = (j0, i_n, i_n + 1, j3)
        for k in range(5):
            weights = azimuth_read_weights(*(cols[j, k] for j in taps), w, l0, l1, l2, l3)
            want = 2.0 * sum(wt * cols[j, k] for wt, j in zip(weights, taps, strict=True))
            np.testing.assert_allclose(out[k], want, rtol=2e-6)


def test_weights_within_the_snap_read_the_texel():
    """:func:`snap_to_texel`: 0 and 1 within :data:`TEXEL_SNAP` (the rounding of the mappings at the texels, up to
    1e-11), the weight itself elsewhere, and monotonic."""
    assert TEXEL_SNAP == 1e-9
    for w, want in ((0.0, 0.0), (1e-11, 0.0), (1.0 - 1e-11, 1.0), (1.0, 1.0), (2e-9, 2e-9), (0.5, 0.5),
                    (1.0 - 2e-9, 1.0 - 2e-9)):
        assert snap_to_texel(w) == want
    ws = np.linspace(0.0, 1.0, 10001)
    assert np.all(np.diff([snap_to_texel(w) for w in ws]) >= 0.0)
