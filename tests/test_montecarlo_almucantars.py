"""Views of one almucantar traced as one (``kernels`` module docstring, "Almucantars"; ``driver.almucantars``).

* The grouping and the turned suns: rings by zenith angle, each view's sun turned about the vertical so that the
  traced view sees it as the view sees the sun (angle to the view, elevation and the side of the view's vertical
  plane all kept); no sharing where the symmetry does not hold (a cloud field, a footprint, irradiance entries, an
  origin off the planet's axis) or where the kernel has no cloud code (the clear sky's).
* Unbiased: a thin water cloud (optical depth 0.5, so the aureole makes the sky 4-17 times brighter towards the sun
  than away from it on one almucantar) with 3 almucantars x 8 azimuths, the sun between two views' azimuths,
  against the same views traced one by one (independent seeds): every value within 4 combined standard errors.
  A sun turned the wrong way shows each view another azimuth's sky (tens of standard errors off).
* Views of distinct zenith angles are traced exactly as before (the same bits as with the sharing off), and the
  shared results do not depend on the task sizes or the threads.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyscatter.atmosphere import AtmosphereParameters, DensityProfile
from skyscatter.atmosphere.clouds import CloudField, CloudLayer
from skyscatter.atmosphere.particles import AnalyticParticles
from skyscatter.montecarlo import driver, sky_radiance
from skyscatter.montecarlo.dataset import almucantar_directions, equal_area_directions

WL = [450.0, 650.0]


def _layer(tau: float) -> AtmosphereParameters:
    return AtmosphereParameters(ground_albedo=0.2, particles=(CloudLayer(1000.0, 1500.0, tau,
                                                                         effective_radius=10e-6),))


def _one_by_one(medium, origins, jitter, dirs, mode, sun):
    n = dirs.shape[0]
    return np.arange(n), np.arange(n + 1), np.tile(sun, (n, 1))


def _views():
    """3 almucantars x 8 azimuths (10, 55, ... deg), listed in a shuffled order."""
    zen, az = np.radians([20.0, 50.0, 80.0]), np.radians(np.arange(10.0, 360.0, 45.0))
    z, a = np.meshgrid(zen, az, indexing="ij")
    d = np.stack([np.sin(z) * np.sin(a), np.sin(z) * np.cos(a), np.cos(z)], -1).reshape(-1, 3)
    return d[np.random.default_rng(5).permutation(d.shape[0])]


def test_almucantar_directions_layout():
    d = almucantar_directions(4, 6)
    assert d.shape == (24, 3)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0, rtol=1e-15)
    np.testing.assert_allclose(d[:, 2].reshape(4, 6), np.repeat([[0.875], [0.625], [0.375], [0.125]], 6, 1))
    az = np.degrees(np.arctan2(d[:6, 0], d[:6, 1])) % 360.0
    np.testing.assert_allclose(az, [30.0, 90.0, 150.0, 210.0, 270.0, 330.0])
    with pytest.raises(ValueError):
        almucantar_directions(0, 6)


def test_rings_and_turned_suns():
    medium = driver.prepare_medium(_layer(5.0), WL)
    dirs = _views()
    n = dirs.shape[0]
    sz, sa = math.radians(60.0), math.radians(30.0)
    sun = np.array([math.sin(sz) * math.sin(sa), math.sin(sz) * math.cos(sa), math.cos(sz)])
    origins = np.tile([0.0, 0.0, medium.bottom_radius], (n, 1))
    order, ptr, suns = driver.almucantars(medium, origins, np.zeros((n, 2)), dirs, np.zeros(n, np.int64), sun)
    assert sorted(order.tolist()) == list(range(n)) and ptr.tolist() == [0, 8, 16, 24]
    for e in range(3):
        ring = order[ptr[e]:ptr[e + 1]]
        assert ring[0] == ring.min() and np.ptp(dirs[ring, 2]) < 1e-12  # first view first, one zenith angle
    first = np.repeat(order[ptr[:-1]], 8)
    # the traced view sees each turned sun as the view sees the sun: angle, elevation and side all kept
    np.testing.assert_allclose(np.einsum("ij,ij->i", dirs[first], suns), dirs[order] @ sun, atol=1e-14)
    np.testing.assert_allclose(suns[:, 2], sun[2], rtol=1e-15)
    np.testing.assert_allclose(np.cross(dirs[first], suns)[:, 2], np.cross(dirs[order], sun)[:, 2], atol=1e-14)
    np.testing.assert_allclose(suns[ptr[:-1]], np.tile(sun, (3, 1)), atol=1e-15)  # the traced view's own sun
    # where the symmetry does not hold, or the kernel has no cloud code: every view alone with the sun
    drops = AnalyticParticles("f", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)
    field = CloudField(np.ones((2, 2, 2)), 1000.0, 1000.0, 2000.0, drops)
    cases = [
        (driver.prepare_medium(AtmosphereParameters(), WL), origins, np.zeros((n, 2)), np.zeros(n, np.int64)),
        (driver.prepare_medium(_layer(5.0), WL, field), origins, np.zeros((n, 2)), np.zeros(n, np.int64)),
        (medium, origins, np.full((n, 2), 10.0), np.zeros(n, np.int64)),
        (medium, origins, np.zeros((n, 2)), np.ones(n, np.int64)),
        (medium, origins + [100.0, 0.0, 0.0], np.zeros((n, 2)), np.zeros(n, np.int64)),
    ]
    for m, o, jit, mode in cases:
        order, ptr, suns = driver.almucantars(m, o, jit, dirs, mode, sun)
        assert order.tolist() == list(range(n)) and ptr.tolist() == list(range(n + 1))
        np.testing.assert_array_equal(suns, np.tile(sun, (n, 1)))


def test_shared_almucantars_are_unbiased(monkeypatch):
    atm = _layer(0.5)
    dirs = _views()
    kw = dict(sun_zenith=math.radians(60.0), sun_azimuth=math.radians(30.0), samples=4096,
              scheduler="synchronous")
    shared = sky_radiance(atm, dirs, WL, seed=21, **kw)
    monkeypatch.setattr(driver, "almucantars", _one_by_one)
    alone = sky_radiance(atm, dirs, WL, seed=22, **kw)
    z = (shared.radiance - alone.radiance) / np.hypot(shared.stderr, alone.stderr)
    assert np.all(np.abs(z) < 4.0), z
    contrast = alone.radiance[:, 0].max() / alone.radiance[:, 0].min()
    assert contrast > 4.0  # the test sees the azimuth: the aureole dominates towards the sun
    # sharing does not change the per-view standard error beyond the noise of its estimate
    ratio = shared.relative_stderr / alone.relative_stderr
    assert 0.8 < float(np.median(ratio)) < 1.25, ratio


def test_distinct_zeniths_are_traced_as_before_and_shared_results_do_not_depend_on_tasks(monkeypatch):
    atm = _layer(5.0)
    kw = dict(sun_zenith=math.radians(50.0), sun_azimuth=math.radians(135.0), samples=600, seed=13)
    fib = equal_area_directions(6)  # no two of one zenith angle
    a = sky_radiance(atm, fib, WL, scheduler="synchronous", **kw)
    with monkeypatch.context() as mp:
        mp.setattr(driver, "almucantars", _one_by_one)
        b = sky_radiance(atm, fib, WL, scheduler="synchronous", **kw)
    np.testing.assert_array_equal(a.radiance, b.radiance)
    np.testing.assert_array_equal(a.stderr, b.stderr)
    rings = almucantar_directions(3, 4)
    ref = sky_radiance(atm, rings, WL, scheduler="synchronous", **kw)
    for sizes in (dict(directions_per_task=1, batches_per_task=1), dict(directions_per_task=2, batches_per_task=3)):
        r = sky_radiance(atm, rings, WL, scheduler=None, **sizes, **kw)
        np.testing.assert_array_equal(r.radiance, ref.radiance)
        np.testing.assert_array_equal(r.stderr, ref.stderr)
    assert np.all(np.isfinite(ref.radiance)) and np.all(ref.radiance > 0.0)
