"""BrunetonSky (sky protocol, any altitude), rendering functions (Eqs. 16-18), camera views and the CLI."""

import argparse
import json
import math

import numpy as np
import pytest

from precomputed_reference import small_earth
from skyscatter.errors import InvalidParameterError, SunBelowHorizonError
from skyscatter.precomputed import AtmosphereParameters, PrecomputedAtmosphere
from skyscatter.render.bruneton import camera_view, fisheye_view, preview_png
from skyscatter.sky.base import SkyModel
from skyscatter.sky.bruneton import BrunetonSky

R = AtmosphereParameters().bottom_radius


@pytest.fixture(scope="module")
def atm():
    return small_earth()


def _directions(n=400, seed=3):
    d = np.random.default_rng(seed).normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def test_protocol_shapes_and_values(atm):
    sky = BrunetonSky(math.radians(40), math.radians(135), precomputed=atm)
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
    sky = BrunetonSky(math.radians(55), math.radians(200), precomputed=atm)
    zen = np.radians(np.linspace(2, 170, 25))
    off = np.radians(np.linspace(5, 175, 19))
    z, o = np.meshgrid(zen, off)
    from skyscatter.conventions import direction_from_angles

    left = sky.luminance(direction_from_angles(z, sky.sun_azimuth - o))
    right = sky.luminance(direction_from_angles(z, sky.sun_azimuth + o))
    np.testing.assert_allclose(left, right, rtol=1e-6)


def test_sun_limits_and_bad_input(atm):
    BrunetonSky(math.radians(101.9), 0.0, precomputed=atm)
    with pytest.raises(SunBelowHorizonError, match=r"precomputed limit.*max_sun_zenith=math.radians"):
        BrunetonSky(math.radians(103.0), 0.0, precomputed=atm)
    with pytest.raises(SunBelowHorizonError, match="inside the atmosphere"):
        BrunetonSky(math.radians(103.0), 0.0, altitude=59e3, precomputed=atm)
    with pytest.raises(InvalidParameterError, match="altitude"):
        BrunetonSky(0.5, 0.0, altitude=-1.0, precomputed=atm)
    with pytest.raises(InvalidParameterError, match="atmosphere"):
        BrunetonSky(0.5, 0.0, atmosphere="earth")


def test_sun_disc_radiance(atm):
    """Solar disc after transmission: E_sun / Omega_sun * T (Eq. 9); dark once the sun has set."""
    sky = BrunetonSky(0.0, 0.0, precomputed=atm)
    t = atm.transmittance(R, 1.0)
    expected = atm.parameters.solar_irradiance_at(atm.wavelengths) / sky.sun_solid_angle * t
    np.testing.assert_allclose(sky.sun_table_radiance(), expected, rtol=1e-6)
    assert sky.sun_xyz()[1] > 1e9  # about 1.6e9 cd m^-2 for the sun at the zenith
    assert np.all(BrunetonSky(math.radians(95), 0.0, precomputed=atm).sun_table_radiance() == 0)
    # from 100 km the same sun, 5 deg below the local horizon, is still visible above the limb
    assert np.all(BrunetonSky(math.radians(95), 0.0, altitude=100e3, precomputed=atm).sun_table_radiance() > 0)


def test_views_from_altitude_and_orbit(atm):
    """From orbit: space is black above the limb, the planet below shows the lit ground; at dusk the night side
    is much darker than the day side."""
    orbit = BrunetonSky(math.radians(40), 0.0, altitude=400e3, precomputed=atm)
    assert orbit.luminance(np.array([0.0, 0.0, 1.0])) == 0.0
    down = orbit.luminance(np.array([0.0, 0.0, -1.0]))
    assert down > 100.0
    dusk = BrunetonSky(math.radians(100), 0.0, altitude=400e3, precomputed=atm)
    assert dusk.luminance(np.array([0.0, 0.0, -1.0])) < 1e-3 * down
    # the limb towards the sun glows: looking just above the horizon of the planet
    limb = -math.acos(R / (R + 400e3))
    d = np.array([0.0, math.cos(limb + 0.01), math.sin(limb + 0.01)])
    assert dusk.luminance(d) > dusk.luminance(np.array([0.0, 0.0, -1.0]))
    # from 10 km the ground below is seen through the atmosphere: darker than the horizon sky
    plane = BrunetonSky(math.radians(50), 0.0, altitude=10e3, precomputed=atm)
    assert plane.luminance(np.array([0.0, 0.0, -1.0])) > 0


def test_earth_shadow_at_dusk(atm):
    """Sun 3 deg below the horizon in the west; looking east. Measured structure (small tables):

    * luminance: the shadow band (1-3 deg elevation, ~33 cd/m^2) is less than 0.6 x the brightest sky above it
      (8-20 deg, ~82 cd/m^2, measured ratio 0.41), and the sky darkens again higher up (30 deg < 0.9 x that peak,
      measured 0.81);
    * colour: the shadow is blue (440/680 nm radiance ratio > 1.5, measured 2.2 at 2 deg), the band above it (the
      Belt of Venus, lit by reddened sunlight) red (ratio < 0.8: the Monte Carlo reference gives 0.87 / 0.71 /
      0.69 +- 0.04 at 8 / 10 / 12 deg, 32768 paths; the tables 0.82 / 0.72 / 0.73) and the sky above turns blue
      again (ratio at 30 deg > 1.5 x the belt's: MC 1.15 / 0.69 = 1.7, tables 1.20 / 0.72 = 1.7).
      With 4 orders and no tail of the later orders the belt came out too red (0.55): the bound was 0.7 then.
    A sky without the Earth's shadow (lit down to the horizon) brightens and reddens towards the horizon.
    """
    sky = BrunetonSky(math.radians(93), math.radians(270), precomputed=atm)
    from skyscatter.conventions import direction_from_angles

    el = np.array([1.0, 2.0, 3.0, 8.0, 10.0, 12.0, 15.0, 20.0, 30.0])
    d = direction_from_angles(np.radians(90.0 - el), np.full(el.size, np.pi / 2))
    lum = sky.luminance(d)
    shadow, belt, high = lum[:3], lum[3:8], lum[8]
    assert shadow.max() < 0.6 * belt.max()
    assert high < 0.9 * belt.max()
    rad = sky.table_radiance(d)
    blue_red = rad[:, np.argmin(atm.wavelengths)] / rad[:, np.argmax(atm.wavelengths)]
    assert np.all(blue_red[:3] > 1.5)
    assert blue_red[3:6].min() < 0.8
    assert blue_red[8] > 1.5 * blue_red[3:8].min()


def test_sun_below_the_observers_horizon_seen_from_orbit(atm):
    """From 400 km the sun stays above the limb down to a zenith of about 109.8 deg, beyond the tables' 102 deg:
    the limit applies where each ray enters the atmosphere, so the view changes across 102 deg as it does for
    the same sun step just before, and the lit limb fades as the sun sets behind the planet."""
    from skyscatter.conventions import equirect_directions

    d = equirect_directions(48, 24)
    lum = {z: BrunetonSky(math.radians(z), 0.0, altitude=4e5, precomputed=atm).luminance(d)
           for z in (101.7, 101.9, 102.1)}
    # 0.2 deg steps move the terminator: the change across 102 deg is like the change just before it
    step_before = np.abs(lum[101.9] - lum[101.7]).sum()
    step_across = np.abs(lum[102.1] - lum[101.9]).sum()
    assert 0 < step_across < 1.5 * step_before < 0.1 * lum[101.9].sum()
    peaks = [BrunetonSky(math.radians(z), 0.0, altitude=4e5, precomputed=atm).luminance(d).max()
             for z in (105.0, 109.0, 112.0, 150.0)]
    assert peaks[0] > peaks[1] > peaks[2] > 0 and peaks[3] == 0
    sun = BrunetonSky(math.radians(105.0), 0.0, altitude=4e5, precomputed=atm).sun_xyz()
    assert sun[1] > 1e8  # the disc is still above the limb
    assert np.all(BrunetonSky(math.radians(115.0), 0.0, altitude=4e5, precomputed=atm).sun_xyz() == 0)


def test_positions_inside_the_planet_are_refused(atm):
    with pytest.raises(InvalidParameterError, match="on or above the planet's surface"):
        atm.sky_radiance(np.array([0.0, 0.0, 6.0e6]), np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, 1.0]))
    # rounding below the surface (< 1 m) is accepted and gives the surface value
    at = atm.sky_radiance(np.array([0.0, 0.0, R]), np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.6, 0.8]))
    just = atm.sky_radiance(np.array([0.0, 0.0, R - 0.5]), np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.6, 0.8]))
    np.testing.assert_allclose(just, at, rtol=1e-6)


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
    sky = BrunetonSky(math.acos(0.8), 0.0, altitude=100.0, precomputed=atm)
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
    assert _cli(["export-luts", "--out-dir", str(tmp_path / "luts"), "--from", str(tmp_path / "t.npz"), "--formats",
                 "raw"], monkeypatch, tmp_path) == 0
    desc = json.loads((tmp_path / "luts" / "atmosphere.json").read_text())
    assert desc["sizes"]["scattering"] == [4, 16, 4, 4]
    assert _cli(["precompute", *small], monkeypatch, tmp_path) == 0
    assert _cli(["precompute", *small], monkeypatch, tmp_path) == 0
    assert "already cached" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        _cli(["precompute", "--scattering-size", "4x16x4"], monkeypatch, tmp_path)


SMALL_CLI = ["--scattering-size", "4x16x4x4", "--transmittance-size", "32x8", "--irradiance-size", "8x4",
             "--orders", "2", "--no-progress"]


def test_cli_precompute_rebuilds_a_corrupt_cache(monkeypatch, tmp_path, capsys):
    """Finding: after rebuilding a damaged cache file the CLI reported "already cached" and no timings."""
    from skyscatter.precomputed.cache import cache_dir, clear_memory_cache

    clear_memory_cache()
    assert _cli(["precompute", *SMALL_CLI], monkeypatch, tmp_path) == 0
    capsys.readouterr()
    (path,) = cache_dir().glob("*.npz")
    data = bytearray(path.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 64] = bytes(b ^ 0xFF for b in data[mid:mid + 64])  # always a change (zeros may be there)
    path.write_bytes(bytes(data))
    clear_memory_cache()
    assert _cli(["precompute", *SMALL_CLI], monkeypatch, tmp_path) == 0
    out, err = capsys.readouterr()
    assert "already cached" not in out and "order 2 multiple" in out and f"wrote {path}" in out
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("skyscatter: warning: rebuilding cached atmosphere tables")
    assert PrecomputedAtmosphere.load(path).orders == 2
    # --force recomputes (timings printed) over the valid file
    clear_memory_cache()
    assert _cli(["precompute", "--force", *SMALL_CLI], monkeypatch, tmp_path) == 0
    out = capsys.readouterr().out
    assert "already cached" not in out and "order 2 multiple" in out
    clear_memory_cache()


def test_cli_help_texts():
    from skyscatter.cli import export_luts, precompute

    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers(dest="command")
    precompute.register(sub)
    export_luts.register(sub)
    text = sub.choices["export-luts"].format_help()
    flat = " ".join(text.split())
    for name in ("transmittance.raw", "irradiance.raw", "single_rayleigh_scattering.raw",
                 "single_mie_scattering.raw", "multiple_scattering.raw", "scattering.raw", "scattering_rgba.raw",
                 "atmosphere.json"):
        assert name in flat
    assert "The files are written together: all appear" in flat
    flat = " ".join(sub.choices["precompute"].format_help().split())
    for default in ("(default: 256x64)", "(default: 64x16)", "(default: 32x128x32x8)"):
        assert default in flat
    args = parser.parse_args(["precompute"])
    assert args.transmittance_size == (256, 64) and args.scattering_size == (32, 128, 32, 8)


def test_cli_export_from_a_junk_file(monkeypatch, tmp_path):
    from skyscatter.errors import FileFormatError

    junk = tmp_path / "junk.npz"
    np.savez(junk, metadata=np.array([{"a": 1}], dtype=object))
    text = tmp_path / "text.npz"
    text.write_text("not a zip")
    for bad in (junk, text):
        with pytest.raises(FileFormatError, match="not a readable skyscatter table file") as info:
            _cli(["export-luts", "--out-dir", str(tmp_path / "luts"), "--from", str(bad)], monkeypatch, tmp_path)
        assert "pickle" not in str(info.value)


def test_renderer_entry_points(atm):
    """The module-level functions for landscape renderers match the methods (Eqs. 16-18)."""
    from skyscatter.aerial import bruneton as aerial

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
    # one observer: the slice lookup (same interpolation, other order of the sums; float32 tables)
    np.testing.assert_allclose(shafts[0], lit[0], rtol=1e-6)
    assert np.all(shafts[1] < lit[1])


@pytest.mark.parametrize("sun_elevation", [10.0, 4.0, 1.0, 0.0, -2.0, -4.0, -6.0])
def test_no_seams_between_neighbouring_view_elevations(atm, sun_elevation):
    """Issue 11 item 2: luminance along view elevations -2..20 deg in 0.01 deg steps, at azimuths from the sun's to
    the opposite one. Every lookup is a multilinear interpolation in coordinates that are continuous in the view
    direction, and the colour conversion is continuous in the samples, so the luminance is continuous and
    piecewise smooth: a step between neighbours is bounded by the local slope. Bound: each step at most 4 times the
    mean step over the surrounding 0.5 deg (a jump J inside the window raises the ratio towards 51; the slope of
    neighbouring interpolation cells differs by less than 3x, measured 1.7-2.6), and under 1 % (0.2-0.6 %
    measured; before the fix the 3-wavelength colour guard switched rules at once: 13-25 % steps, ratio 27-49).
    The 0.5 deg on either side of the horizon itself are left out (the ground's edge)."""
    from scipy.ndimage import uniform_filter1d

    sky = BrunetonSky(math.radians(90.0 - sun_elevation), 0.0, precomputed=atm)
    az = np.radians([0.0, 2.0, 10.0, 30.0, 90.0, 180.0])
    el = np.radians(np.arange(-2.0, 20.0 + 1e-9, 0.01))
    a, e = np.meshgrid(az, el, indexing="ij")
    lum = sky.luminance(np.stack([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)], axis=-1))
    assert np.all(lum > 0)
    step = np.abs(np.diff(lum, axis=1)) / np.minimum(lum[:, 1:], lum[:, :-1])
    local = uniform_filter1d(step, 51, axis=1, mode="nearest")
    away = np.abs(np.degrees(0.5 * (e[:, 1:] + e[:, :-1]))) > 0.5
    assert step[away].max() < 0.01
    assert np.max(step[away] / (local[away] + 1e-6)) < 4.0


@pytest.mark.parametrize("altitude, sun_elevation", [(0.0, 30.0), (0.0, 1.0), (0.0, -4.0), (10.0, 30.0), (30.0, -4.0),
                                                    (8000.0, 10.0)])
def test_observer_slices_equal_the_4d_lookup(atm, altitude, sun_elevation, monkeypatch):
    """One observer and one sun: the lookups on 2D slices of the tables (lookup.observer_slices) give what the
    general 4D kernel gives, spectrum and XYZ, sky and ground (to float32 rounding of the tables: 1e-6); also within
    the cell of rows touching the ground (10 and 30 m), where each row is read at its own mu coordinate (the
    slices then hold the two rows' shares apart). In twilight with the stored texels' read
    (``compute_twilight_single`` False; the computed single scattering is tested against the Monte Carlo,
    tests/test_precomputed_low_sun.py)."""
    from skyscatter.precomputed.tables import PrecomputedAtmosphere as PA

    monkeypatch.setattr(atm, "compute_twilight_single", False)

    spectral = PA(atm.parameters, np.linspace(400.0, 700.0, 16), atm.sizes, atm.orders,
                  {k: np.repeat(v[..., :1], 16, axis=-1) * np.linspace(1.0, 0.5, 16) for k, v in atm.tables.items()})
    pos = np.array([0.0, 0.0, R + altitude])
    e = math.radians(sun_elevation)
    sun = np.array([0.0, math.cos(e), math.sin(e)])
    d = _directions(3000, seed=11)
    many = np.broadcast_to(pos, d.shape)  # positions per ray: the general kernel
    for tables in (atm, spectral):
        np.testing.assert_allclose(tables.sky_radiance(pos, d, sun), tables.sky_radiance(many, d, sun),
                                   rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(spectral.sky_xyz(pos, d, sun), spectral.to_xyz(spectral.sky_radiance(many, d, sun)),
                               rtol=1e-6, atol=1e-9)
    # luminance alone (one projected channel) is the Y of the three
    np.testing.assert_allclose(spectral.sky_luminance(pos, d, sun), spectral.sky_xyz(pos, d, sun)[:, 1],
                               rtol=1e-12, atol=1e-15)
    # spectra at other wavelengths: the slices projected to them equal the resampled general lookup
    wl = np.arange(380.0, 781.0, 10.0)
    np.testing.assert_allclose(spectral.sky_spectrum(pos, d, sun, wl),
                               spectral.resample(spectral.sky_radiance(many, d, sun), wl), rtol=1e-6, atol=1e-12)
    # unnormalised directions are normalised; invalid ones are refused with the library's error
    np.testing.assert_allclose(spectral.sky_xyz(pos, 3.0 * d[:5], sun), spectral.sky_xyz(pos, d[:5], sun), rtol=1e-12)
    from skyscatter.errors import InvalidDirectionError

    for bad in ([[0.0, 0.0, 0.0]], [[np.nan, 0.0, 1.0]], [[np.inf, 0.0, 1.0]], [[1.0, 0.0]]):
        with pytest.raises(InvalidDirectionError):
            spectral.sky_xyz(pos, bad, sun)


def test_wavelengths_option_chooses_the_tables(atm, monkeypatch):
    """BrunetonSky(tables="rgb" | "spectral") asks the cache for those tables; not with tables given."""
    import skyscatter.precomputed.cache as cache

    asked = []

    def fake(params=None, **kwargs):
        asked.append(kwargs.get("tables"))
        return atm

    monkeypatch.setattr(cache, "cached_atmosphere", fake)
    sky = BrunetonSky(0.5, 0.0, tables="rgb", ozone_column=250.0)
    BrunetonSky(0.5, 0.0)
    assert asked == ["rgb", None]
    assert sky.model_parameters()["tables"] == "rgb"
    with pytest.raises(InvalidParameterError, match="not with precomputed tables"):
        BrunetonSky(0.5, 0.0, precomputed=atm, tables="rgb")
    with pytest.raises(InvalidParameterError, match="'spectral' or 'rgb'"):
        BrunetonSky(0.5, 0.0, tables="blue")


def test_sun_exactly_at_the_tables_limit_is_not_dark(atm):
    """A sun at the tables' largest zenith angle (max_sun_zenith, accepted by BrunetonSky) lies on the last texel:
    the lookups keep it (MU_S_LIMIT_TOLERANCE) instead of dropping it by a rounding of mu_s below mu_s_min, which
    made the whole sky black (review of the vectorised kernels). The value continues the sky inside the limit:
    the lookup is linear in a coordinate that is smooth there, so the straight line through the suns 1e-9 and
    2e-9 rad inside reaches it to second order (~1e-7; the first sun-zenith cell is steep, the values themselves
    differ by up to 4e-4)."""
    limit = atm.parameters.max_sun_zenith
    d = np.array([[0.0, 0.3, 1.0], [0.2, -0.9, 0.3], [0.0, 0.99, 0.05]])
    for altitude in (0.0, 1000.0):
        lum = [BrunetonSky(limit - k * 1e-9, 0.0, precomputed=atm, altitude=altitude).luminance(d) for k in (0, 1, 2)]
        assert np.all(lum[0] > 0.0)
        np.testing.assert_allclose(lum[0], 2.0 * lum[1] - lum[2], rtol=1e-6)


def test_irradiance_and_sun_lookups_refuse_points_below_the_ground(atm):
    """Points below the surface (the planet's centre: NaN from the kernels' divisions) are refused with the
    library's error; points outside the atmosphere stay allowed."""
    sun = np.array([0.0, 0.0, 1.0])
    for bad in ([0.0, 0.0, 0.0], [0.0, 0.0, R - 1000.0]):
        with pytest.raises(InvalidParameterError, match="below the surface"):
            atm.sun_transmittance(bad, sun)
        with pytest.raises(InvalidParameterError, match="below the surface"):
            atm.ground_irradiance(bad, [0.0, 0.0, 1.0], sun)
    assert np.all(np.isfinite(atm.sun_transmittance([0.0, 0.0, R + 1.0e6], sun)))
