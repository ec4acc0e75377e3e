"""The protocol's solar disc (SolarDisc): what images, photometry and the landscape read from every sun-aware sky."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyscatter import HosekWilkieSky, PreethamSky
from skyscatter.conventions import direction_from_angles
from skyscatter.render.sky_image import sky_image
from skyscatter.sky.hosek_wilkie import SOLAR_RADIUS
from skyscatter.spectral import HDR_SCALE


def test_hosek_wilkie_limb_darkening_has_mean_one_and_matches_the_2013_disc():
    sky = HosekWilkieSky(math.radians(40.0), 1.0, turbidity=3.0)
    wl = np.array([400.0, 550.0, 700.0])
    sun = sky.sun
    assert sun.limb_darkening is not None and sun.angular_radius == SOLAR_RADIUS
    # solid-angle mean over the disc (small-angle: area weight 2 r dr) is 1
    x, w = np.polynomial.legendre.leggauss(64)
    r = 0.5 * (x + 1.0)
    mean = (sun.limb_darkening(r, wl) * (w * r)[:, None]).sum(axis=0)
    np.testing.assert_allclose(mean, 1.0, rtol=1e-4)
    # across the disc at the centre's elevation: disc average x darkening = the 2013 solar radiance
    for frac in (0.0, 0.5, 0.9):
        d = direction_from_angles(math.radians(40.0), 1.0 + frac * SOLAR_RADIUS / math.sin(math.radians(40.0)))
        ratio = sky.solar_radiance(d, wl) / (sun.spectral_radiance(wl) * sun.limb_darkening(frac, wl))
        np.testing.assert_allclose(ratio, 1.0, rtol=1e-5)
    assert np.all(sun.limb_darkening(1.2, wl) == 0.0)


@pytest.mark.parametrize("sky", [PreethamSky(2.5, math.radians(50.0), 2.0),
                                 HosekWilkieSky(math.radians(50.0), 2.0, turbidity=3.0)], ids=["uniform", "limb"])
def test_sky_image_draws_the_disc_with_its_irradiance(sky):
    """A fine fisheye resolves the disc: summed pixel luminance x solid angle = the disc's normal illuminance."""
    from skyscatter.render.sky_image import pixel_solid_angles

    size = 8001  # about 0.023 mrad per pixel: the 0.26-0.27 deg disc spans ~400 pixels
    fov = math.radians(1.2)
    d_sun = sky.sun.direction
    heading = math.degrees(math.atan2(d_sun[0], d_sun[1]))
    pitch = 90.0 - math.degrees(math.acos(d_sun[2]))
    img_sun = sky_image(sky, projection="pinhole", width=size // 20, height=size // 20, heading=math.radians(heading),
                        pitch=math.radians(pitch), fov=fov, ground_albedo=None, dtype=np.float64)
    img_sky = sky_image(sky, projection="pinhole", width=size // 20, height=size // 20, heading=math.radians(heading),
                        pitch=math.radians(pitch), fov=fov, ground_albedo=None, sun_disc=False, dtype=np.float64)
    omega = pixel_solid_angles("pinhole", size // 20, size // 20, fov=fov)
    from skyscatter.spectral import linear_srgb_to_xyz

    y = linear_srgb_to_xyz(img_sun - img_sky)[..., 1] / HDR_SCALE
    assert float((y * omega).sum()) == pytest.approx(sky.sun.illuminance_normal(), rel=1e-6)
