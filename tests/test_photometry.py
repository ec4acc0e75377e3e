"""Illuminance by numerical integration: analytic cases, an independent adaptive quadrature, patch sums, the sun."""

import math

import numpy as np
import pytest

from skyscatter import photometry
from skyscatter.conventions import direction_from_angles
from skyscatter.errors import InvalidParameterError
from skyscatter.patches import patch_scheme
from skyscatter.sky.base import LuminanceOnlySky
from skyscatter.sky.cie import CIEOvercastSky, CIEStandardSky
from skyscatter.sky.perez import PerezSky


class UniformSky(LuminanceOnlySky):
    """A sky of constant luminance L above the horizon."""

    def __init__(self, value):
        self.value = value

    def luminance(self, d):
        d = np.asarray(d)
        return np.where(d[..., 2] >= 0, self.value, 0.0)


def test_uniform_sky_gives_pi_l():
    """Horizontal: pi L; vertical: pi L / 2; tilted by beta: pi L (1 + cos beta) / 2 (sky view factor)."""
    sky = UniformSky(2500.0)
    assert photometry.horizontal_illuminance(sky) == pytest.approx(math.pi * 2500.0, rel=1e-12)
    assert photometry.vertical_illuminance(sky, 1.0) == pytest.approx(math.pi * 2500.0 / 2, rel=1e-12)
    for beta in (0.3, 1.0, 2.0, 3.0):
        expected = math.pi * 2500.0 * (1 + math.cos(beta)) / 2
        assert photometry.tilted_illuminance(sky, beta, 2.5) == pytest.approx(expected, rel=1e-9)
    assert photometry.tilted_illuminance(sky, math.pi, 0.0) == 0.0


def test_cie_overcast_closed_forms():
    """D_v / L_z = 7 pi / 9; vertical: (pi / 6 + 4 / 9) L_z, from integrating (1 + 2 cos theta)/3 by hand."""
    sky = CIEOvercastSky(zenith_luminance=3000.0)
    assert photometry.horizontal_illuminance(sky) == pytest.approx(3000.0 * 7 * math.pi / 9, rel=1e-12)
    assert photometry.vertical_illuminance(sky, 0.4) == pytest.approx(3000.0 * (math.pi / 6 + 4 / 9), rel=1e-10)


def test_quadrature_weights():
    d, w = photometry.plane_quadrature()
    assert np.all(d[:, 2] >= 0) and np.all(w > 0)
    assert w.sum() == pytest.approx(math.pi, rel=1e-13)
    d, w = photometry.plane_quadrature(math.pi / 2, math.pi)  # facing south
    assert np.all(d[:, 1] <= 1e-12) and np.all(d[:, 2] >= 0)


@pytest.mark.parametrize(
    "sky",
    [
        CIEStandardSky(15, math.radians(40), 0.5, zenith_luminance=1000.0),
        PerezSky(math.radians(25), 0.5, epsilon=9.0, delta=0.15, diffuse_illuminance=15_000.0),
        PerezSky(math.radians(60), 0.5, epsilon=1.03, delta=0.2, diffuse_illuminance=8_000.0),
    ],
    ids=["cie15", "perez-clear", "perez-overcast"],
)
@pytest.mark.parametrize("tilt,azimuth", [(0.0, 0.0), (math.pi / 2, 0.5), (math.pi / 3, 4.0)])
def test_against_adaptive_scipy_quadrature(sky, tilt, azimuth):
    """scipy quad_vec (adaptive Gauss-Kronrod in theta) x a fine periodic trapezoid in phi: independent rule."""
    from scipy.integrate import quad_vec

    normal = direction_from_angles(tilt, azimuth)
    phi = np.linspace(0, 2 * np.pi, 4097)[:-1]

    def ring(theta):
        d = direction_from_angles(theta, phi)
        cos_inc = np.clip(d @ normal, 0.0, None)
        return np.array([np.mean(sky.luminance(d) * cos_inc) * 2 * np.pi * math.sin(theta)])

    ref, _ = quad_vec(ring, 0.0, math.pi / 2, epsrel=1e-6, points=[abs(math.pi / 2 - tilt), sky.sun_zenith])
    value = photometry.tilted_illuminance(sky, tilt, azimuth)
    assert value == pytest.approx(float(ref[0]), rel=2e-4)


@pytest.mark.parametrize("sky", [CIEStandardSky(12, 0.8, 2.0), PerezSky(0.8, 2.0, epsilon=4.0, delta=0.2)],
                         ids=["cie12", "perez"])
def test_patch_cells_integrate_to_the_same_illuminance(sky):
    """Midpoint rule over the 2305 x 16 equal-area Reinhart MF=4 cells vs the Gauss rule: within 0.05 %."""
    g = patch_scheme("reinhart4")
    cells = g.sample_directions(4)
    per_patch = (sky.luminance(cells) * cells[..., 2]).mean(axis=-1)
    assert float(per_patch @ g.solid_angles) == pytest.approx(photometry.horizontal_illuminance(sky), rel=5e-4)


def test_global_illuminance_adds_the_sun_on_each_plane():
    sky = PerezSky(math.radians(50), math.radians(180), direct_normal_irradiance=700.0,
                   diffuse_horizontal_irradiance=100.0)
    e_sun = sky.sun_illuminance_normal
    assert photometry.sun_normal_illuminance(sky) == e_sun
    diffuse = photometry.horizontal_illuminance(sky)
    assert photometry.global_horizontal_illuminance(sky) == pytest.approx(diffuse + e_sun * math.cos(math.radians(50)))
    south = photometry.vertical_illuminance(sky, math.pi, include_sun=True)
    assert south == pytest.approx(photometry.vertical_illuminance(sky, math.pi) + e_sun * math.sin(math.radians(50)))
    north = photometry.vertical_illuminance(sky, 0.0, include_sun=True)
    assert north == pytest.approx(photometry.vertical_illuminance(sky, 0.0))
    assert photometry.sun_plane_illuminance(sky, math.pi / 2, 0.0) == 0.0


def test_sun_of_a_spectral_model():
    import skyscatter

    sky = skyscatter.PreethamSky(3.0, 0.7, 1.0)
    e = photometry.sun_normal_illuminance(sky)
    assert e == pytest.approx(float(sky.sun_xyz()[1]) * sky.sun_solid_angle)
    assert 30_000 < e < 130_000


def test_bad_input():
    sky = CIEOvercastSky()
    with pytest.raises(InvalidParameterError):
        photometry.horizontal_illuminance(sky, include_sun=True)
    with pytest.raises(InvalidParameterError):
        photometry.tilted_illuminance(sky, -0.1, 0.0)
    with pytest.raises(InvalidParameterError):
        photometry.tilted_illuminance(sky, 1.0, float("nan"))
    with pytest.raises(InvalidParameterError):
        photometry.plane_quadrature(nodes=(1, 10))
