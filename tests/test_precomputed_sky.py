"""BrunetonSky (sky protocol, any altitude), rendering functions (Eqs. 16-18), camera views and the CLI."""

import argparse
import json
import math

import numpy as np
import pytest

from skyscatter.errors import InvalidParameterError, SunBelowHorizonError
from skyscatter.precomputed import AtmosphereParameters, PrecomputedAtmosphere
from skyscatter.precomputed.sky import BrunetonSky
from skyscatter.precomputed.views import camera_view, fisheye_view, preview_png
from skyscatter.sky.base import SkyModel
from test_precomputed_reference import small_earth

R = AtmosphereParameters().bottom_radius


@pytest.fixture(scope="module")
def atm():
    return small_earth()


def _directions(n=400, seed=3):
    d = np.random.default_rng(seed).normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def test_protocol_shapes_and_values(atm):
    sky = BrunetonSky(math.radians(40), math.radians(135), atmosphere=atm)
    assert isinstance(sky, SkyModel) and sky.renders_ground and sky.has_sun
    d = _directions().reshape(20, 20, 3)
    wl = np.arange(380.0, 781.0, 10.0)
    spec = sky.spectral_radiance(d, wl)
    xyz = sky.xyz(d)
    lum = sky.luminance(d)
    assert spec.shape == (20, 20, wl.size) and xyz.shape == (20, 20, 3) and lum.shape == (20, 20)
    assert np.all(np.isfinite(spec)) and np.all(spec >= 0) and np.all(lum > 0)
    np.testing.assert_allclose(lum, xyz[..., 1])
    # integrating the reconstructed spectrum with the observer reproduces xyz (same spectral model, 1 %)
    from skyscatter.spectral import spectrum_to_xyz

    ref_wl = np.arange(360.0, 831.0, 1.0)
    np.testing.assert_allclose(spectrum_to_xyz(sky.spectral_radiance(d, ref_wl), ref_wl), xyz, rtol=0.01)


def test_symmetric_about_the_solar_meridian(atm):
    """The sky is a mirror image about the vertical plane through the sun (atol 1e-9 relative)."""
    sky = BrunetonSky(math.radians(55), math.radians(200), atmosphere=atm)
    zen = np.radians(np.linspace(2, 170, 25))
    off = np.radians(np.linspace(5, 175, 19))
    z, o = np.meshgrid(zen, off)
    from skyscatter.conventions import direction_from_angles

    left = sky.luminance(direction_from_angles(z, sky.sun_azimuth - o))
    right = sky.luminance(direction_from_angles(z, sky.sun_azimuth + o))
    np.testing.assert_allclose(left, right, rtol=1e-6)


def test_sun_limits_and_bad_input(atm):
    BrunetonSky(math.radians(101.9), 0.0, atmosphere=atm)
    with pytest.raises(SunBelowHorizonError, match="precomputed limit"):
        BrunetonSky(math.radians(103.0), 0.0, atmosphere=atm)
    with pytest.raises(InvalidParameterError, match="altitude"):
        BrunetonSky(0.5, 0.0, altitude=-1.0, atmosphere=atm)
    with pytest.raises(InvalidParameterError, match="atmosphere"):
        BrunetonSky(0.5, 0.0, atmosphere="earth")


def test_sun_disc_radiance(atm):
    """Solar disc after transmission: E_sun / Omega_sun * T (Eq. 9); dark once the sun has set."""
    sky = BrunetonSky(0.0, 0.0, atmosphere=atm)
    t = atm.transmittance(R, 1.0)
    expected = atm.parameters.solar_irradiance_at(atm.wavelengths) / sky.sun_solid_angle * t
    np.testing.assert_allclose(sky.sun_table_radiance(), expected, rtol=1e-6)
    assert sky.sun_xyz()[1] > 1e9  # about 1.6e9 cd m^-2 for the sun at the zenith
    assert np.all(BrunetonSky(math.radians(95), 0.0, atmosphere=atm).sun_table_radiance() == 0)
    # from 100 km the same sun, 5 deg below the local horizon, is still visible above the limb
    assert np.all(BrunetonSky(math.radians(95), 0.0, altitude=100e3, atmosphere=atm).sun_table_radiance() > 0)


def test_views_from_altitude_and_orbit(atm):
    """From orbit: space is black above the limb, the planet below shows the lit ground; at dusk the night side
    is much darker than the day side."""
    orbit = BrunetonSky(math.radians(40), 0.0, altitude=400e3, atmosphere=atm)
    assert orbit.luminance(np.array([0.0, 0.0, 1.0])) == 0.0
    down = orbit.luminance(np.array([0.0, 0.0, -1.0]))
    assert down > 100.0
    dusk = BrunetonSky(math.radians(100), 0.0, altitude=400e3, atmosphere=atm)
    assert dusk.luminance(np.array([0.0, 0.0, -1.0])) < 1e-3 * down
    # the limb towards the sun glows: looking just above the horizon of the planet
    limb = -math.acos(R / (R + 400e3))
    d = np.array([0.0, math.cos(limb + 0.01), math.sin(limb + 0.01)])
    assert dusk.luminance(d) > dusk.luminance(np.array([0.0, 0.0, -1.0]))
    # from 10 km the ground below is seen through the atmosphere: darker than the horizon sky
    plane = BrunetonSky(math.radians(50), 0.0, altitude=10e3, atmosphere=atm)
    assert plane.luminance(np.array([0.0, 0.0, -1.0])) > 0


def test_earth_shadow_at_dusk(atm):
    """Sun 2 deg below the horizon in the west: looking east, the sky just above the horizon (in the Earth's
    shadow) is darker than the band a few degrees higher (the Belt of Venus)."""
    sky = BrunetonSky(math.radians(92), math.radians(270), atmosphere=atm)
    from skyscatter.conventions import direction_from_angles

    elevations = np.radians([1.0, 3.0, 6.0, 10.0, 15.0])
    lum = sky.luminance(direction_from_angles(np.pi / 2 - elevations, np.full(5, np.pi / 2)))
    assert lum[0] < lum.max()


def test_aerial_perspective_and_light_shafts(atm):
    """Eq. 16: T L_obj + inscatter; inscatter grows and transmittance falls with distance; a shadowed length
    (Eq. 17) removes inscattered light, all of it when the whole ray is in shadow."""
    sun = np.array([0.0, 0.6, 0.8])
    cam = np.array([0.0, 0.0, R + 100.0])
    dist = np.array([1e3, 1e4, 5e4])
    pts = cam + dist[:, None] * np.array([1.0, 0.0, 0.0])
    t, s = atm.aerial_perspective(cam, pts, sun)
    assert np.all(np.diff(t[:, 1]) < 0) and np.all(np.diff(s[:, 1]) > 0)
    assert np.all((t > 0) & (t <= 1))
    _, s_half = atm.aerial_perspective(cam, pts, sun, shadow_length=dist / 2)
    _, s_all = atm.aerial_perspective(cam, pts, sun, shadow_length=dist)
    assert np.all(s_half < s) and np.all(s_all == 0)
    # Eq. 18 for the sky: shadow near the camera removes light too
    sky = atm.sky_radiance(cam, np.array([1.0, 0.0, 0.05]) / np.hypot(1, 0.05), sun)
    shafts = atm.sky_radiance(cam, np.array([1.0, 0.0, 0.05]) / np.hypot(1, 0.05), sun, shadow_length=5e3)
    assert np.all(shafts < sky)
    # the same through BrunetonSky's local frame (observer 100 m above the surface point at the origin)
    sky = BrunetonSky(math.acos(0.8), 0.0, altitude=100.0, atmosphere=atm)
    t_local, s_local = sky.aerial_perspective(dist[:, None] * np.array([1.0, 0.0, 0.0]) + [0.0, 0.0, 100.0])
    np.testing.assert_allclose(t_local, t, rtol=1e-12)
    np.testing.assert_allclose(s_local, s, rtol=1e-12)
    # ground irradiance: sun on a horizontal surface equals E_sun T mu_s
    e_sun, e_sky = atm.ground_irradiance(np.array([0.0, 0.0, R]), np.array([0.0, 0.0, 1.0]), sun)
    expected = atm.parameters.solar_irradiance_at(atm.wavelengths) * atm.transmittance(R, 0.8) * 0.8
    np.testing.assert_allclose(e_sun, expected, rtol=1e-6)
    assert np.all(e_sky > 0) and np.all(e_sky < e_sun)


def test_camera_views_and_preview(atm, tmp_path):
    img = camera_view(atm, math.radians(60), math.radians(180), altitude=400e3, pitch=-0.3, fov=1.2, width=64,
                      height=48)
    assert img.shape == (48, 64, 3) and np.all(np.isfinite(img))
    assert np.all(img[0] == 0)  # top row: black space
    fish = fisheye_view(atm, math.radians(96), math.radians(270), size=32, output="xyz")
    assert np.all(fish[..., 1] >= 0) and fish[16, 16, 1] > 0
    path = preview_png(img, tmp_path / "orbit.png")
    from PIL import Image

    assert Image.open(path).size == (64, 48)


def _cli(argv, monkeypatch, tmp_path):
    from skyscatter.cli import export_luts, precompute

    monkeypatch.setenv("SKYSCATTER_CACHE_DIR", str(tmp_path / "cache"))
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="command")
    precompute.register(sub)
    export_luts.register(sub)
    args = parser.parse_args(argv)
    return args.func(args)


def test_cli_precompute_and_export(monkeypatch, tmp_path, capsys):
    small = ["--scattering-size", "4x16x4x4", "--transmittance-size", "32x8", "--irradiance-size", "8x4",
             "--orders", "2", "--no-progress"]
    assert _cli(["precompute", "--out", str(tmp_path / "t.npz"), *small], monkeypatch, tmp_path) == 0
    out = capsys.readouterr().out
    assert "order 2 multiple" in out and "wrote" in out
    assert PrecomputedAtmosphere.load(tmp_path / "t.npz").orders == 2
    assert _cli(["export-luts", "--out-dir", str(tmp_path / "luts"), "--from", str(tmp_path / "t.npz")],
                monkeypatch, tmp_path) == 0
    desc = json.loads((tmp_path / "luts" / "atmosphere.json").read_text())
    assert desc["sizes"]["scattering"] == [4, 16, 4, 4]
    assert _cli(["precompute", *small], monkeypatch, tmp_path) == 0
    assert _cli(["precompute", *small], monkeypatch, tmp_path) == 0
    assert "already cached" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        _cli(["precompute", "--scattering-size", "4x16x4"], monkeypatch, tmp_path)


def test_renderer_entry_points(atm):
    """The module-level functions for landscape renderers match the methods (Eqs. 16-18)."""
    from skyscatter.precomputed import aerial

    sun = np.array([0.0, 0.6, 0.8])
    cam = np.array([0.0, 0.0, R + 50.0])
    pts = cam + np.array([[2e4, 0.0, -40.0], [0.0, 3e4, 500.0]])
    t, s = aerial.aerial_perspective(cam, pts, sun, atmosphere=atm)
    t2, s2 = atm.aerial_perspective(cam, pts, sun)
    np.testing.assert_array_equal(t, t2)
    np.testing.assert_array_equal(s, s2)
    _, s_sh = aerial.aerial_perspective_shafts(cam, pts, sun, np.array([5e3, 1e4]), atmosphere=atm)
    assert np.all(s_sh < s)
    d = np.array([[1.0, 0.0, 0.1], [0.0, 1.0, 0.3]])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    lit = atm.sky_radiance(cam, d, sun)
    shafts = aerial.sky_radiance_shafts(cam, d, sun, np.array([0.0, 2e4]), atmosphere=atm)
    np.testing.assert_array_equal(shafts[0], lit[0])
    assert np.all(shafts[1] < lit[1])
