import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from skyscatter.conventions import (
    angle_between,
    angles_from_direction,
    as_directions,
    direction_from_angles,
    equirect_directions,
    fisheye_directions,
    pinhole_directions,
)
from skyscatter.errors import InvalidDirectionError, InvalidParameterError


def test_cardinal_directions():
    np.testing.assert_allclose(direction_from_angles(0.0, 0.0), [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(direction_from_angles(math.pi / 2, 0.0), [0, 1, 0], atol=1e-15)  # north
    np.testing.assert_allclose(direction_from_angles(math.pi / 2, math.pi / 2), [1, 0, 0], atol=1e-15)  # east


@given(st.floats(0.01, math.pi - 0.01), st.floats(0, 2 * math.pi - 1e-9))
def test_angles_round_trip(zenith, azimuth):
    z, a = angles_from_direction(direction_from_angles(zenith, azimuth))
    assert z == pytest.approx(zenith, abs=1e-9)
    assert math.cos(a - azimuth) == pytest.approx(1.0, abs=1e-9)


def test_angle_between_accurate_for_small_angles():
    a = direction_from_angles(0.5, 0.0)
    b = direction_from_angles(0.5 + 1e-7, 0.0)
    assert float(angle_between(a, b)) == pytest.approx(1e-7, rel=1e-6)
    assert float(angle_between([0, 0, 1], [0, 0, -1])) == pytest.approx(math.pi)


def test_as_directions_validates():
    with pytest.raises(InvalidDirectionError, match=r"\(\.\.\., 3\)"):
        as_directions([1.0, 2.0])
    with pytest.raises(InvalidDirectionError, match="NaN"):
        as_directions([[0, 0, 1], [np.nan, 0, 1]])
    with pytest.raises(InvalidDirectionError, match="zero-length"):
        as_directions([0, 0, 0])
    np.testing.assert_allclose(as_directions([0, 0, 2]), [0, 0, 1])


def test_equirect_layout():
    d = equirect_directions(360, 180)
    assert d.shape == (180, 360, 3)
    assert d[0, 0, 2] > 0.999 and d[-1, 0, 2] < -0.999  # zenith on top, nadir at the bottom
    mid = 90
    np.testing.assert_allclose(d[mid, 180], [0, 1, 0], atol=0.02)  # centre column: north
    np.testing.assert_allclose(d[mid, 270], [1, 0, 0], atol=0.02)  # three quarters: east
    np.testing.assert_allclose(d[mid, 90], [-1, 0, 0], atol=0.02)  # one quarter: west
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0)


def test_fisheye_layout():
    d, inside = fisheye_directions(101)
    assert d.shape == (101, 101, 3)
    np.testing.assert_allclose(d[50, 50], [0, 0, 1], atol=1e-12)
    assert d[0, 50, 1] > 0.99  # top edge: north horizon
    assert d[50, 0, 0] > 0.99  # left edge: east (view from below)
    assert not inside[0, 0] and inside[50, 50]


def test_pinhole_axis_and_orientation():
    d = pinhole_directions(5, 3, heading=math.pi / 2, pitch=0.0, fov=1.0)
    np.testing.assert_allclose(d[1, 2], [1, 0, 0], atol=1e-12)  # looks east
    assert d[1, 4, 1] < 0  # right of the image is south when looking east
    assert d[0, 2, 2] > 0  # top row looks up
    with pytest.raises(InvalidParameterError):
        pinhole_directions(4, 3, heading=0, pitch=0, fov=0)
    with pytest.raises(InvalidParameterError):
        pinhole_directions(0, 3, heading=0, pitch=0, fov=1)
