"""Radiance's formats (issue 18, item 6), read and rendered by Radiance's own binaries (pyradiance).

* matrix files: ``rmtxop`` reads what ``write_radiance_matrix`` writes (ascii, float, double); ``skymatrix
  --format radiance`` has gendaymtx's layout and agrees with gendaymtx on the same weather; ``dctimestep`` with a
  horizontal-illuminance daylight coefficient row gives back the matrix's own horizontal illuminance.
* ``sky --format radiance``: ``rtrace -I`` at the ground gives photometry's horizontal illuminance (sun included)
  within 1 % (issue 18; measured 0.04 %); an ``rpict`` angular fisheye matches skyscatter's fisheye of the same sky.

Radiance's luminance of an RGB radiance: ``179 (0.265 R + 0.670 G + 0.065 B)`` (its color.h).
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

pyradiance = pytest.importorskip("pyradiance")

from skyscatter import photometry  # noqa: E402
from skyscatter.cli import main  # noqa: E402
from skyscatter.conventions import fisheye_directions  # noqa: E402
from skyscatter.radiance import read_radiance_matrix, write_radiance_matrix  # noqa: E402
from skyscatter.render import sky_image  # noqa: E402
from skyscatter.sky import registry  # noqa: E402
from skyscatter.sky_matrix import skymatrix  # noqa: E402
from skyscatter.spectral import HDR_SCALE, linear_srgb_to_xyz  # noqa: E402

BIN = pyradiance.BINPATH
LIB = os.path.join(os.path.dirname(pyradiance.__file__), "lib")
DATA = Path(__file__).parent / "data"
WEIGHTS = 179.0 * np.array([0.265, 0.670, 0.065])


def run(*args, cwd=None, stdin=None) -> bytes:
    env = dict(os.environ, RAYPATH=os.pathsep.join([".", LIB]))
    res = subprocess.run([os.path.join(BIN, str(args[0])), *map(str, args[1:])], input=stdin, capture_output=True,
                         env=env, cwd=cwd)
    assert res.returncode == 0, res.stderr.decode()
    return res.stdout


@pytest.mark.parametrize("encoding", ["ascii", "float", "double"])
def test_rmtxop_reads_our_matrices(tmp_path, encoding):
    values = np.random.default_rng(3).random((4, 5, 3)) * 100.0
    path = write_radiance_matrix(tmp_path / "a.mtx", values, header=["made by the test"], encoding=encoding)
    (tmp_path / "b.mtx").write_bytes(run("rmtxop", "-fd", path))  # Radiance re-encodes it as doubles
    back, keys = read_radiance_matrix(tmp_path / "b.mtx")
    assert keys["NROWS"] == "4" and keys["NCOLS"] == "5" and keys["NCOMP"] == "3"
    np.testing.assert_allclose(back, values, rtol=1e-5 if encoding == "ascii" else 1e-7)  # %.6g
    assert read_radiance_matrix(path)[0].shape == (4, 5, 3)


@pytest.fixture(scope="module")
def weather(tmp_path_factory):
    folder = tmp_path_factory.mktemp("weather")
    epw = folder / "weather.epw"
    shutil.copy(DATA / "weather.epw", epw)
    run("epw2wea", epw, folder / "weather.wea")
    (folder / "gendaymtx.mtx").write_bytes(run("gendaymtx", "-m", "1", folder / "weather.wea"))
    return folder


def test_sky_matrix_has_gendaymtx_layout_and_values(weather, tmp_path):
    """Same rows (ground + 145 Tregenza patches), columns (48 hours) and RGB; the patch-centre Perez sky of
    gendaymtx: ground within 0.3 %, sky total within 1 %, correlation over every entry > 0.9999
    (measured: 1.0006, 0.9963, 0.99995; the small difference is gendaymtx's own sun position and its three-hour
    dew point)."""
    m = skymatrix(weather / "weather.epw", scheme="tregenza", include_sun=True, samples=1)
    ours_path = m.save_radiance(tmp_path / "ours.mtx")
    theirs, _ = read_radiance_matrix(weather / "gendaymtx.mtx")
    ours, keys = read_radiance_matrix(ours_path)
    assert ours.shape == theirs.shape == (146, 48, 3)
    assert keys["FORMAT"] == "float" and keys["LATLONG"] == "48.14000000 11.58000000"
    lt, lo = theirs @ WEIGHTS, ours @ WEIGHTS
    assert lo[0].sum() / lt[0].sum() == pytest.approx(1.0, abs=3e-3)
    assert lo[1:].sum() / lt[1:].sum() == pytest.approx(1.0, abs=1e-2)
    assert np.corrcoef(lo.ravel(), lt.ravel())[0, 1] > 0.9999
    # Radiance's luminance of our patches is our luminance (sky colour and white sun both weigh 1.000)
    np.testing.assert_allclose(lo[1:].T, m.luminance, rtol=5e-4, atol=1e-9)


def test_dctimestep_gives_the_horizontal_illuminance(weather, tmp_path):
    """A daylight-coefficient row of Omega_p sin(altitude_p) (0 for the ground) through dctimestep: per hour the
    matrix's own horizontal illuminance (colour weights: 2e-4)."""
    m = skymatrix(weather / "weather.epw", scheme="reinhart2", include_sun=True, samples=1)
    sky = m.save_radiance(tmp_path / "sky.mtx")
    g = m.scheme
    dc = np.zeros((1, g.n_patches + 1, 3))
    dc[0, 1:, :] = (g.solid_angles * np.sin(g.centre_altitude))[:, None]
    write_radiance_matrix(tmp_path / "dc.mtx", dc, encoding="ascii")
    (tmp_path / "out.mtx").write_bytes(run("dctimestep", tmp_path / "dc.mtx", sky))
    out, _ = read_radiance_matrix(tmp_path / "out.mtx")
    np.testing.assert_allclose(out[0] @ WEIGHTS, m.horizontal_illuminance(), rtol=5e-4, atol=1e-6)


def test_cli_skymatrix_radiance_is_read_by_rmtxop(weather, tmp_path, capsys):
    out = tmp_path / "year.smx"
    code = main(["skymatrix", str(weather / "weather.epw"), "--format", "radiance", "--patches", "tregenza",
                 "--ground-albedo", "0.35", "--out", str(out), "--no-progress"])
    assert code == 0, capsys.readouterr().err
    lum = run("rmtxop", "-fa", "-c", 0.265, 0.670, 0.065, out).split(b"\n\n", 1)[1]
    values = np.array(lum.split(), dtype=float).reshape(146, 48)
    m = skymatrix(weather / "weather.epw", scheme="tregenza")
    ground = 0.35 * (m.diffuse_illuminance + m.sun_illuminance_normal * np.maximum(np.cos(m.sun_zenith), 0)) / np.pi
    np.testing.assert_allclose(values[0] * 179.0, ground, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("model,extra", [("preetham", {}), ("hosek-wilkie", {}),
                                          ("cie", {"sun_illuminance_normal": 70000.0})])
def test_radiance_sky_renders_our_illuminance_and_fisheye(tmp_path, capsys, model, extra):
    """``sky --format radiance``, then oconv, rtrace -I (-ab 1, 8192 hemisphere samples, no caching) and rpict
    -vta (-ab 0, unjittered pixel centres)."""
    zen, azi = math.radians(52.0), math.radians(140.0)
    sky = registry.build(model, zen, azi, **extra)
    args = ["sky", "--model", model, "--sun-elevation", "38", "--sun-azimuth", "140", "--format", "radiance",
            "--width", "1024", "--out", str(tmp_path / "sky.rad")]
    if extra:
        args += ["--sun-illuminance", "70000"]
    assert main(args) == 0, capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sky.cal", "sky.hdr", "sky.png", "sky.rad"]
    (tmp_path / "sky.oct").write_bytes(run("oconv", "sky.rad", cwd=tmp_path))
    rgb = np.array(run("rtrace", "-I", "-h", "-w", "-ab", 1, "-ad", 8192, "-as", 0, "-aa", 0, "-lw", 1e-7,
                       "sky.oct", cwd=tmp_path, stdin=b"0 0 0 0 0 1\n").split(), dtype=float)
    expected = photometry.horizontal_illuminance(sky, include_sun=True)
    assert float(rgb @ WEIGHTS) == pytest.approx(expected, rel=1e-2)
    n = 160
    (tmp_path / "fish.hdr").write_bytes(run("rpict", "-vta", "-vp", 0, 0, 0, "-vd", 0, 0, 1, "-vu", 0, 1, 0, "-vh", 180,
                                            "-vv", 180, "-x", n, "-y", n, "-pj", 0, "-ps", 1, "-ab", 0, "sky.oct",
                                            cwd=tmp_path))
    theirs = np.frombuffer(run("pvalue", "-h", "-H", "-dd", tmp_path / "fish.hdr"), dtype="<f8").reshape(n, n, 3)
    ours = linear_srgb_to_xyz(sky_image(sky, projection="fisheye", width=n, sun_disc=False, ground_albedo=None,
                                        dtype=np.float64))[..., 1] / HDR_SCALE
    d, inside = fisheye_directions(n)
    # away from the sun (the light source seen directly) and from the horizon circle's edge pixels
    keep = inside & (d @ sky.sun_direction < math.cos(math.radians(3.0))) & (d[..., 2] > 0.03)
    ratio = (theirs @ WEIGHTS)[keep] / ours[keep]
    assert np.median(ratio) == pytest.approx(1.0, abs=3e-3)  # measured 1.0007 (preetham)
    assert np.percentile(np.abs(ratio - 1.0), 95) < 0.015  # the picture's 0.35 deg pixels: measured 0.6 %
