"""The cloud field container (skyscatter.atmosphere.clouds): validation, geometry, files, procedural fields."""

from __future__ import annotations

import itertools
import math

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


# [Perlin2002]'s 12 edge gradients, written out again for the straightforward evaluation below
_EDGE_GRADIENTS = [(1, 1, 0), (-1, 1, 0), (1, -1, 0), (-1, -1, 0), (1, 0, 1), (-1, 0, 1), (1, 0, -1), (-1, 0, -1),
                   (0, 1, 1), (0, -1, 1), (0, 1, -1), (0, -1, -1)]


def _fbm_by_definition(point, period, octaves, seed, octave_value):
    """Fractal sum at one point, octave by octave (frequency x2, amplitude /2, normalised to amplitude 1), with
    each octave's random table drawn as the docstrings of perlin_fbm / worley_fbm say (one generator of the seed,
    octaves in order)."""
    rng = np.random.default_rng(seed)
    total, norm = 0.0, 0.0
    for o in range(octaves):
        per = [p * 2**o for p in period]
        total += 0.5**o * octave_value([c * 2**o for c in point], per, rng)
        norm += 0.5**o
    return total / norm


def _perlin_octave(p, per, rng):
    """Gradient noise at one point: the fade-weighted sum over the cell's 2^d corners of the corner's gradient
    dotted with the offset from the corner ([Perlin2002])."""
    grads = rng.integers(0, 12, size=tuple(per))
    cell = [math.floor(c) for c in p]
    value = 0.0
    for corner in itertools.product((0, 1), repeat=len(p)):
        node = tuple((cell[k] + corner[k]) % per[k] for k in range(len(p)))
        g = _EDGE_GRADIENTS[grads[node]]
        weight, dot = 1.0, 0.0
        for k in range(len(p)):
            t = p[k] - cell[k]
            fade = 6 * t**5 - 15 * t**4 + 10 * t**3
            weight *= fade if corner[k] else 1.0 - fade
            dot += g[k] * (t - corner[k])
        value += weight * dot
    return value


def _inverted_worley_octave(p, per, rng):
    """1 - distance to the nearest feature point (one per cell, at the cell's corner + a uniform offset) of the
    3^d cells around the point, the lattice wrapped with the period ([Worley1996])."""
    feats = rng.random(tuple(per) + (len(p),))
    cell = [math.floor(c) for c in p]
    nearest = math.inf
    for off in itertools.product((-1, 0, 1), repeat=len(p)):
        nb = [cell[k] + off[k] for k in range(len(p))]
        fp = feats[tuple(nb[k] % per[k] for k in range(len(p)))]
        nearest = min(nearest, math.dist(p, [nb[k] + fp[k] for k in range(len(p))]))
    return 1.0 - nearest


@pytest.mark.parametrize("period", [(3, 2), (2, 3, 1)])
def test_compiled_noise_is_the_noise_of_its_definition(period):
    # points across the period and beyond it (negative and past one period: the wrap-around), a few octaves
    rng = np.random.default_rng(11)
    pts = (rng.random((12, len(period))) * 3.0 - 1.0) * np.array(period)
    for octaves, seed in ((1, 0), (3, 4)):
        perlin = perlin_fbm(pts, period, octaves, seed)
        worley = worley_fbm(pts, period, octaves, seed)
        for i, p in enumerate(pts.tolist()):
            assert perlin[i] == pytest.approx(_fbm_by_definition(p, period, octaves, seed, _perlin_octave),
                                              rel=0.0, abs=1e-13)
            assert worley[i] == pytest.approx(_fbm_by_definition(p, period, octaves, seed, _inverted_worley_octave),
                                              rel=0.0, abs=1e-13)
    with pytest.raises(InvalidParameterError, match="2 or 3 coordinates"):
        perlin_fbm(np.zeros((4, 4)), (1, 1, 1, 1), 1, 0)
    with pytest.raises(InvalidParameterError, match="whole numbers >= 1"):
        worley_fbm(pts, period[:-1], 1, 0)
    with pytest.raises(InvalidParameterError, match="whole numbers >= 1"):
        perlin_fbm(pts, (0,) * len(period), 1, 0)


def test_procedural_fields_are_those_of_the_stored_references():
    # SHA-256 of the grids made by the numpy evaluation of the noise (commit b252cdb), which made the Monte Carlo
    # references of tests/data/broken_cloud_*: the compiled noise must give the same fields to the last bit
    small = CloudField.procedural(cover=0.4, base=1000.0, top=3000.0, particles=DROPS, optical_depth=12.0,
                                  size=8000.0, resolution=(48, 40, 12), feature_size=2000.0, seed=7)
    assert small.digest() == "71711009e05ba9d6aa0d2fae7133c5dea59d479d3296ee0a5e780ecde4469160"
    bench = CloudField.procedural(cover=0.4, base=1000.0, top=2500.0, particles=DROPS, optical_depth=10.0,
                                  size=16_000.0, resolution=(128, 128, 32), feature_size=4000.0, seed=1)
    assert bench.digest() == "163a071eb42ff42bba329e364b83ab5690a3579e0e48115c40c94d48e4953483"
