"""The cloud field container (skyscatter.atmosphere.clouds): validation, geometry, files, procedural fields."""

from __future__ import annotations

import numpy as np
import pytest

from skyscatter.atmosphere import DensityProfile
from skyscatter.atmosphere.clouds import CloudField, perlin_fbm, worley_fbm
from skyscatter.atmosphere.particles import AnalyticParticles
from skyscatter.errors import FileFormatError, InvalidParameterError, OutputError

DROPS = AnalyticParticles("droplets", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)


def test_step_cloud_is_the_i3rc_case_1():
    f = CloudField.i3rc_step_cloud(DROPS)
    assert f.shape == (32, 1, 1) and f.periodic
    assert f.voxel_size[0] == pytest.approx(15.625) and f.base == 0.0 and f.top == 250.0
    tau = f.optical_depth()[:, 0]
    np.testing.assert_allclose(tau[:16], 2.0)
    np.testing.assert_allclose(tau[16:], 18.0)
    x, _, z = f.coordinates()
    assert x[0] == pytest.approx(7.8125) and z[0] == pytest.approx(125.0)


@pytest.mark.parametrize("kw, message", [
    (dict(extinction=np.zeros((2, 2))), "3D array"),
    (dict(extinction=-np.ones((2, 2, 2))), "finite and in"),
    (dict(extinction=np.full((2, 2, 2), np.nan)), "finite and in"),
    (dict(size=0.0), "size"),
    (dict(base=500.0, top=400.0), "above its base"),
    (dict(base=-1.0), "base"),
    (dict(particles="water"), "particle component"),
    (dict(periodic="yes"), "periodic"),
])
def test_bad_fields_are_refused(kw, message):
    args = dict(extinction=np.ones((2, 2, 2)) * 1e-3, size=1000.0, base=500.0, top=800.0, particles=DROPS)
    args.update(kw)
    ext = args.pop("extinction")
    with pytest.raises(InvalidParameterError, match=message):
        CloudField(ext, args.pop("size"), args.pop("base"), args.pop("top"), args.pop("particles"), **args)


def test_liquid_water_content_gives_the_extinction_of_large_droplets():
    """beta = 3 Q LWC / (4 rho_w r_e) with Q = 2: 0.3 g m^-3 at r_e = 10 um -> 0.045 m^-1 (tau 45 per km)."""
    f = CloudField.from_liquid_water_content(np.full((1, 1, 1), 3e-4), 1000.0, 0.0, 1000.0, DROPS, 10e-6)
    assert f.extinction[0, 0, 0] == pytest.approx(0.045)
    with pytest.raises(InvalidParameterError, match="effective radius"):
        CloudField.from_liquid_water_content(np.ones((1, 1, 1)) * 1e-4, 1000.0, 0.0, 1000.0, DROPS, 1.0)


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_save_and_load_round_trip(tmp_path, suffix):
    rng = np.random.default_rng(0)
    f = CloudField(rng.random((4, 3, 2)) * 0.01, (800.0, 600.0), 300.0, 700.0, DROPS, origin=(-100.0, 50.0),
                   periodic=False)
    path = f.save(tmp_path / f"field{suffix}")
    g = CloudField.load(path)
    np.testing.assert_array_equal(g.extinction, f.extinction)
    assert g.size == pytest.approx(f.size) and g.origin == pytest.approx(f.origin)
    assert (g.base, g.top, g.periodic) == (300.0, 700.0, False)
    assert g.particles.to_dict() == DROPS.to_dict()
    assert g.digest() == f.digest()
    if suffix == ".zarr":
        with pytest.raises(OutputError, match="not overwritten"):
            f.save(path)


def test_load_refuses_what_is_not_a_field(tmp_path):
    with pytest.raises(FileFormatError, match="no such"):
        CloudField.load(tmp_path / "missing.nc")
    bad = tmp_path / "bad.nc"
    bad.write_text("not netcdf")
    with pytest.raises(FileFormatError, match="not a readable"):
        CloudField.load(bad)
    with pytest.raises(OutputError, match=r"\.nc .* \.zarr"):
        CloudField.i3rc_step_cloud(DROPS).save(tmp_path / "field.txt")


def test_procedural_field_has_the_requested_cover_and_optical_depth():
    kw = dict(cover=0.4, base=1000.0, top=3000.0, particles=DROPS, optical_depth=12.0, size=8000.0,
              resolution=(48, 40, 12), feature_size=2000.0, seed=7)
    f = CloudField.procedural(**kw)
    tau = f.optical_depth()
    # the coverage map is thresholded at its 60 % quantile; erosion removes a little cloud at the edges
    assert 0.30 < f.cloud_fraction() <= 0.41
    assert tau[tau > 0].mean() == pytest.approx(12.0, rel=1e-9)
    again = CloudField.procedural(**kw)
    assert again.digest() == f.digest()
    assert CloudField.procedural(**{**kw, "seed": 8}).digest() != f.digest()
    # overcast: every column cloudy
    full = CloudField.procedural(**{**kw, "cover": 1.0})
    assert full.cloud_fraction() > 0.97
    assert CloudField.procedural(**{**kw, "cover": 0.0}).cloud_fraction() == 0.0
    with pytest.raises(InvalidParameterError, match="cloud cover"):
        CloudField.procedural(**{**kw, "cover": 1.5})


def test_noise_is_periodic_and_bounded():
    pts = np.random.default_rng(1).random((500, 3)) * 4.0
    per = np.array([4, 4, 4])
    a = perlin_fbm(pts, per, 3, 5)
    b = perlin_fbm(pts + per * np.array([1, 0, 0]), per, 3, 5)
    np.testing.assert_allclose(a, b, atol=1e-12)
    assert np.all(np.abs(a) < 1.0)
    w = worley_fbm(pts, per, 2, 5)
    np.testing.assert_allclose(w, worley_fbm(pts + per * np.array([0, 1, 1]), per, 2, 5), atol=1e-12)
    assert np.all((w >= 0.0) & (w <= 1.0))
