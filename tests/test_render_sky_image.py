import math

import numpy as np
import pytest

from skyscatter import PreethamSky
from skyscatter.errors import FileFormatError, InvalidParameterError, OutputError
from skyscatter.render import pixel_solid_angles, read_exr, sky_image, tonemap, write_exr, write_png
from skyscatter.spectral import HDR_SCALE, linear_srgb_to_xyz


@pytest.fixture(scope="module")
def sky():
    return PreethamSky(2.5, math.radians(50), math.radians(120))


@pytest.mark.parametrize("projection,width,height", [("equirect", 64, 32), ("fisheye", 48, 48), ("pinhole", 40, 30)])
def test_pixel_solid_angles_sum(projection, width, height):
    omega = pixel_solid_angles(projection, width, height, fov=math.radians(60))
    if projection == "equirect":
        assert omega.sum() == pytest.approx(4 * math.pi, rel=1e-3)
    elif projection == "fisheye":
        from skyscatter.conventions import fisheye_directions

        _, inside = fisheye_directions(width)
        assert omega[inside].sum() == pytest.approx(2 * math.pi, rel=2e-2)  # pixelated circle edge
    else:
        # closed form of a rectangular pyramid: 4 asin(sin(a) sin(b)), a, b the half angles
        a = math.radians(30)
        b = math.atan(math.tan(a) * height / width)
        assert omega.sum() == pytest.approx(4 * math.asin(math.sin(a) * math.sin(b)), rel=1e-3)


def test_sky_image_matches_model_and_scale(sky):
    img = sky_image(sky, width=64, sun_disc=False, ground_albedo=None, dtype=np.float64)
    assert img.shape == (32, 64, 3) and img.dtype == np.float64
    from skyscatter.conventions import equirect_directions

    d = equirect_directions(64)
    y = linear_srgb_to_xyz(img)[..., 1] / HDR_SCALE
    upper = d[..., 2] > 0
    np.testing.assert_allclose(y[upper], sky.luminance(d[upper]), rtol=1e-9)
    assert np.all(img[~upper] == 0)


def test_fisheye_outside_circle_black(sky):
    img = sky_image(sky, projection="fisheye", width=32, sun_disc=False, ground_albedo=None)
    assert np.all(img[0, 0] == 0) and np.all(img[16, 16] > 0)


def test_sun_disc_flux_independent_of_resolution(sky):
    # The disc adds the sun's normal illuminance E = L_sun * Omega_sun at any image size (splatted when the
    # sun is smaller than a pixel, drawn as a disc when larger); exact since the disc is deposited with the
    # pixel grid's bilinear kernel (issue 18; it was within 15 % at 4096 before).
    expected = sky.sun_xyz()[1] * sky.sun_solid_angle
    for width in (64, 4096):
        with_sun = sky_image(sky, width=width, ground_albedo=None, dtype=np.float64)
        without = sky_image(sky, width=width, sun_disc=False, ground_albedo=None, dtype=np.float64)
        extra = (linear_srgb_to_xyz(with_sun - without)[..., 1] / HDR_SCALE) * pixel_solid_angles("equirect", width)
        assert extra.sum() == pytest.approx(expected, rel=1e-9)


def test_bad_arguments(sky):
    with pytest.raises(InvalidParameterError):
        sky_image(sky, projection="mercator", width=8)
    with pytest.raises(InvalidParameterError):
        sky_image(sky, width=0)
    with pytest.raises(InvalidParameterError):
        sky_image(sky, width=8, ground_albedo=1.5)


def test_exr_round_trip(tmp_path, rng):
    img = rng.random((5, 7, 3)).astype(np.float32) * 1e4
    path = write_exr(tmp_path / "a.exr", img)
    np.testing.assert_array_equal(read_exr(path), img)


def test_exr_refuses_nan_and_leaves_nothing(tmp_path):
    img = np.ones((2, 2, 3), dtype=np.float32)
    img[0, 0, 0] = np.nan
    with pytest.raises(InvalidParameterError):
        write_exr(tmp_path / "bad.exr", img)
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_on_failure_keeps_old_file(tmp_path, monkeypatch):
    target = tmp_path / "keep.png"
    target.write_bytes(b"old")
    from PIL import Image

    def boom(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(Image.Image, "save", boom)
    with pytest.raises(RuntimeError):
        write_png(target, np.ones((2, 2, 3)))
    assert target.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.png"]


def test_unwritable_folder(tmp_path):
    with pytest.raises(OutputError, match="does not exist"):
        write_exr(tmp_path / "missing" / "a.exr", np.ones((1, 1, 3)))


def test_read_exr_errors(tmp_path):
    with pytest.raises(FileFormatError):
        read_exr(tmp_path / "none.exr")
    bad = tmp_path / "bad.exr"
    bad.write_bytes(b"not an exr")
    with pytest.raises(FileFormatError):
        read_exr(bad)


def test_png_written(tmp_path, sky):
    from PIL import Image

    img = sky_image(sky, projection="fisheye", width=16, ground_albedo=None)
    p = write_png(tmp_path / "s.png", img)
    assert Image.open(p).size == (16, 16)


def test_tonemap_monotonic_and_bounded(rng):
    y = np.sort(rng.random(200) * 1e4)
    rgb = np.stack([y, y, y], axis=-1)[None]
    out = tonemap(rgb, auto=False, exposure_ev=-10)[0, :, 0]
    assert np.all(np.diff(out) >= 0) and out.min() >= 0 and out.max() <= 1
    assert tonemap(np.full((1, 1, 3), np.nan)).max() == 0
