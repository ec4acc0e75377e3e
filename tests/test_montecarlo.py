"""Statistics, determinism, schedulers and bad input of skyscatter.montecarlo.

Reproducibility contract (docs/montecarlo.md): for a fixed seed the result is bit-identical whatever the task
sizes and the scheduler (synchronous, threaded, a LocalCluster with worker processes).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.atmosphere import phase as phase_np
from skyscatter.errors import InvalidDirectionError, InvalidParameterError
from skyscatter.montecarlo import sky_radiance
from skyscatter.montecarlo.rng import uniforms

EARTH = AtmosphereParameters()
DIRS = np.array([[0.0, 0.0, 1.0], [0.0, 0.7, 0.7], [0.5, -0.5, 0.3]])


# ----------------------------------------------------------------------------------------------- phase functions
# The kernels call the numba scalar functions of skyscatter.atmosphere.phase; these tests call the same compiled
# functions one value at a time (the numpy versions are tested in test_atmosphere_medium.py).


def _numba_samples(kind: str, u: np.ndarray, g: float = 0.0) -> np.ndarray:
    """``mu`` from the numba inverse CDF the kernels use, one call per uniform number."""
    if kind == "rayleigh":
        f = phase_np.rayleigh_inverse_cdf_scalar
        return np.array([f(float(x)) for x in u])
    f = phase_np.henyey_greenstein_inverse_cdf_scalar
    return np.array([f(float(x), float(g)) for x in u])


@pytest.mark.parametrize("mu", [-1.0, -0.3, 0.0, 0.5, 0.99, 1.0])
def test_numba_phase_functions_equal_the_numpy_ones(mu):
    """Same formulas as skyscatter.atmosphere.phase (Rayleigh; HG 1941; Cornette-Shanks 1992 Eq. 8)."""
    assert phase_np.rayleigh_phase_scalar(mu) == pytest.approx(float(phase_np.rayleigh_phase(mu)), rel=1e-14)
    assert phase_np.henyey_greenstein_scalar(mu, 0.8) == pytest.approx(float(phase_np.henyey_greenstein(mu, 0.8)),
                                                                       rel=1e-14)
    assert phase_np.cornette_shanks_scalar(mu, 0.8) == pytest.approx(float(phase_np.cornette_shanks(mu, 0.8)),
                                                                     rel=1e-14)
    # the kernels sample a Cornette-Shanks aerosol as HG and weight the path by p_CS / p_HG
    assert (phase_np.henyey_greenstein_scalar(mu, 0.8) * float(phase_np.cornette_shanks_hg_weight(mu, 0.8))
            == pytest.approx(phase_np.cornette_shanks_scalar(mu, 0.8), rel=1e-14))


def test_aerosol_kinds_of_the_kernels():
    """The phase functions the driver passes to the kernels: Rayleigh, the aerosol's (Cornette-Shanks or
    Henyey-Greenstein with its g), none for ozone and for an absent cloud field."""
    from skyscatter.montecarlo import kernels
    from skyscatter.montecarlo.driver import prepare_medium

    for name, kind, lobe in (("cornette-shanks", 0, kernels.LOBE_CORNETTE_SHANKS),
                             ("henyey-greenstein", 1, kernels.LOBE_HENYEY_GREENSTEIN)):
        assert phase_np.aerosol_phase_kind(name) == kind
        m = prepare_medium(EARTH.replace(mie_phase_function=name, mie_phase_g=0.7), np.array([550.0]))
        assert m.lobe.tolist() == [kernels.LOBE_RAYLEIGH, lobe, kernels.LOBE_NONE, kernels.LOBE_NONE]
        assert m.lobe_g[1] == 0.7
    assert phase_np.aerosol_phase_scalar(0.3, 0.8, 0) == phase_np.cornette_shanks_scalar(0.3, 0.8)
    assert phase_np.aerosol_phase_scalar(0.3, 0.8, 1) == phase_np.henyey_greenstein_scalar(0.3, 0.8)


@pytest.mark.parametrize("kind, g", [("rayleigh", 0.0), ("henyey-greenstein", 0.8), ("henyey-greenstein", -0.4),
                                     ("henyey-greenstein", 0.0)])
def test_phase_samplers_follow_their_density(kind, g):
    """Histogram of 2e5 samples of mu from the numba inverse CDFs against the integral of the phase function
    over each of 20 bins (chi-square with 19 degrees of freedom below its 99.9 % quantile, 43.8)."""
    from scipy.integrate import quad

    rng = np.random.default_rng(1)
    n = 200_000
    mu = _numba_samples(kind, rng.random(n), g)
    edges = np.linspace(-1, 1, 21)
    counts, _ = np.histogram(mu, edges)
    pdf = (lambda m: 2 * math.pi * phase_np.rayleigh_phase_scalar(m)) if kind == "rayleigh" else (
        lambda m: 2 * math.pi * phase_np.henyey_greenstein_scalar(m, g))
    expect = np.array([quad(pdf, a, b)[0] for a, b in zip(edges[:-1], edges[1:], strict=True)]) * n
    chi2 = np.sum((counts - expect) ** 2 / expect)
    assert chi2 < 43.8, chi2


def test_numba_inverse_cdfs_equal_the_numpy_ones():
    """One formula for numpy and numba: the compiled inverse CDFs agree with the validated numpy functions (to
    1e-15: numpy's and LLVM's cbrt may differ in the last bit) and are increasing in u."""
    u = np.concatenate([[0.0, 0.25, 0.5, 1.0], np.random.default_rng(3).random(2000)])
    np.testing.assert_allclose(_numba_samples("rayleigh", u), phase_np.rayleigh_inverse_cdf(u), rtol=0, atol=2e-15)
    for g in (-0.4, 0.0, 0.8):
        np.testing.assert_array_equal(_numba_samples("henyey-greenstein", u, g),
                                      phase_np.henyey_greenstein_inverse_cdf(u, g))
    s = np.sort(u)
    for kind, g in (("rayleigh", 0.0), ("henyey-greenstein", 0.0), ("henyey-greenstein", 0.8)):
        assert np.all(np.diff(_numba_samples(kind, s, g)) >= 0)
    assert phase_np.rayleigh_inverse_cdf_scalar(0.0) == -1.0 and phase_np.rayleigh_inverse_cdf_scalar(1.0) == 1.0


def test_direction_about_axis_gives_the_requested_angle():
    rng = np.random.default_rng(2)
    for _ in range(200):
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        mu, phi = rng.uniform(-1, 1), rng.uniform(0, 2 * math.pi)
        o = np.array(phase_np.direction_about_axis(*d, mu, phi))
        assert abs(np.linalg.norm(o) - 1) < 1e-12
        assert abs(o @ d - mu) < 1e-12
    # the axis straight down (the branch of Duff et al.'s basis for z < 0) and a right angle to it
    o = np.array(phase_np.direction_about_axis(0.0, 0.0, -1.0, 0.0, 0.3))
    assert abs(o[2]) < 1e-15 and abs(np.linalg.norm(o) - 1) < 1e-15


# ----------------------------------------------------------------------------------------------- RNG


def test_rng_streams_are_uniform_and_distinct():
    u = uniforms(0, 1, 0, 0, 0, 200_000)
    assert abs(u.mean() - 0.5) < 4 * math.sqrt(1 / 12 / u.size)
    assert np.all((u >= 0) & (u < 1))
    a = uniforms(0, 1, 0, 0, 0, 8)
    for other in (uniforms(1, 1, 0, 0, 0, 8), uniforms(0, 2, 0, 0, 0, 8), uniforms(0, 1, 1, 0, 0, 8),
                  uniforms(0, 1, 0, 1, 0, 8), uniforms(0, 1, 0, 0, 1, 8)):
        assert not np.any(a == other)
    np.testing.assert_array_equal(a, uniforms(0, 1, 0, 0, 0, 8))


# ----------------------------------------------------------------------------------------------- statistics


def test_standard_error_shrinks_as_one_over_sqrt_n():
    """16x the samples: the standard error falls by 4 (the median of the 6 ratios within +-10 %), and the two
    estimates agree within 3 combined standard errors. The median, not each ratio: the per-path estimates are
    heavy-tailed (a rare path through the aureole), so a standard error from 512 paths scatters more than a normal
    sample's variance would; over seeds 4-9 (2026-12-05) single ratios ranged 3.11-7.99 while their medians stayed
    within 3.79-4.20, with the stratified error and with the plain per-path one alike."""
    kw = dict(sun_zenith=math.radians(50.0), seed=4, scheduler="synchronous")
    a = sky_radiance(EARTH, DIRS, [450.0, 600.0], samples=512, **kw)
    b = sky_radiance(EARTH, DIRS, [450.0, 600.0], samples=8192, **kw)
    ratio = a.stderr / b.stderr
    assert abs(float(np.median(ratio)) / 4 - 1) < 0.10, ratio
    assert np.all((ratio > 2.0) & (ratio < 10.0)), ratio  # no ratio that a wrong power of N would give
    assert np.all(np.abs(a.radiance - b.radiance) < 3 * np.hypot(a.stderr, b.stderr))


def test_result_does_not_depend_on_task_sizes_or_threads():
    kw = dict(sun_zenith=math.radians(60.0), samples=1500, seed=9)
    ref = sky_radiance(EARTH, DIRS, [400.0, 500.0, 700.0], scheduler="synchronous", **kw)
    for dpt, bpt in ((1, 1), (2, 3), (3, 100)):
        r = sky_radiance(EARTH, DIRS, [400.0, 500.0, 700.0], directions_per_task=dpt, batches_per_task=bpt, **kw)
        np.testing.assert_array_equal(r.radiance, ref.radiance)
        np.testing.assert_array_equal(r.stderr, ref.stderr)
    # a direction's value does not depend on the other directions of the block
    single = sky_radiance(EARTH, DIRS[:1], [400.0, 500.0, 700.0], scheduler="synchronous", **kw)
    np.testing.assert_array_equal(single.radiance[0], ref.radiance[0])
    other = sky_radiance(EARTH, DIRS, [400.0, 500.0, 700.0], scheduler="synchronous", **{**kw, "seed": 10})
    assert not np.any(other.radiance == ref.radiance)


@pytest.mark.slow
def test_identical_on_a_local_cluster_with_two_worker_processes():
    """synchronous == LocalCluster(n_workers=2, threads_per_worker=1, processes=True), bit for bit. Kept small (6
    tasks of 600 paths); most of its time is starting the two worker processes."""
    distributed = pytest.importorskip("distributed")
    kw = dict(sun_zenith=math.radians(45.0), samples=600, seed=21, directions_per_task=1, batches_per_task=1)
    ref = sky_radiance(EARTH, DIRS, [450.0, 550.0], scheduler="synchronous", **kw)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=50) as cluster, distributed.Client(cluster) as client:
        r = sky_radiance(EARTH, DIRS, [450.0, 550.0], scheduler=client, **kw)
        r2 = sky_radiance(EARTH, DIRS, [450.0, 550.0], scheduler=cluster.scheduler_address, **kw)
    np.testing.assert_array_equal(r.radiance, ref.radiance)
    np.testing.assert_array_equal(r.stderr, ref.stderr)
    np.testing.assert_array_equal(r2.radiance, ref.radiance)


def test_result_object():
    r = sky_radiance(EARTH, [0.0, 0.0, 2.0], [550.0], sun_zenith=0.5, samples=700, scheduler="synchronous")
    assert r.radiance.shape == r.stderr.shape == (1, 1)
    assert r.samples == 1024  # two batches of 512
    assert r.seconds > 0
    np.testing.assert_allclose(r.directions, [[0, 0, 1]])
    assert np.all(r.radiance > 0) and np.all(r.stderr > 0)


def test_sun_far_below_horizon_and_observer_in_orbit():
    """Deep night (sun 30 deg below) gives 0. From 400 km, the limb of the atmosphere lies between 18.3 and
    19.8 deg below the horizontal (acos(6420/6760), acos(6360/6760)): 19 deg sees the lit limb, 30 deg the ground
    through the atmosphere, 17 deg and the zenith see black space."""
    night = sky_radiance(EARTH, DIRS, [550.0], sun_zenith=math.radians(120.0), samples=64, scheduler="synchronous")
    assert np.all(night.radiance == 0)
    dips = np.radians([-90.0, 17.0, 19.0, 30.0])
    dirs = np.stack([0 * dips, np.cos(dips), -np.sin(dips)], axis=-1)
    up = sky_radiance(EARTH, dirs, [550.0], sun_zenith=0.3, altitude=400e3, samples=256, scheduler="synchronous")
    assert up.radiance[0, 0] == 0 and up.radiance[1, 0] == 0  # space
    assert up.radiance[2, 0] > 0 and up.radiance[3, 0] > 0  # limb, ground


# ----------------------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize("dirs", [[0.0, 0.0, 0.0], [np.nan, 0.0, 1.0], [np.inf, 0, 1], [1.0, 2.0], []])
def test_bad_directions(dirs):
    with pytest.raises(InvalidDirectionError):
        sky_radiance(EARTH, dirs, [550.0], sun_zenith=0.5, samples=8)


@pytest.mark.parametrize("kw", [
    dict(samples=0), dict(samples=-3), dict(samples=2.5), dict(wavelengths=[100.0]), dict(wavelengths=[2000.0]),
    dict(wavelengths=[np.nan]), dict(wavelengths=[]), dict(altitude=-1.0), dict(altitude=np.nan),
    dict(sun_zenith=4.0), dict(sun_zenith=np.nan), dict(seed=-1), dict(scheduler="bogus"),
    dict(scheduler=3),
])
def test_bad_input(kw):
    args = dict(samples=8, wavelengths=[550.0], sun_zenith=0.5)
    args.update(kw)
    wl = args.pop("wavelengths")
    with pytest.raises(InvalidParameterError):
        sky_radiance(EARTH, DIRS, wl, **args)


# ----------------------------------------------------------------------------------------------- sky model


def test_montecarlo_sky_model_answers_the_protocol():
    from skyscatter.sky.montecarlo import MonteCarloSky
    from skyscatter.sky.registry import build_sky

    sky = build_sky("montecarlo", math.radians(40.0), 1.0, samples=256)
    assert isinstance(sky, MonteCarloSky)
    d = np.array([[[0.0, 0.0, 1.0], [0.3, 0.3, 0.9]], [[0.0, 1.0, 0.1], [1.0, 0.0, 0.2]]])
    wl = [450.0, 550.0]
    L = sky.spectral_radiance(d, wl)
    assert L.shape == (2, 2, 2) and np.all(L > 0)
    # same seed and samples: identical to the driver
    ref = sky_radiance(EARTH, d.reshape(-1, 3), wl, sun_zenith=math.radians(40.0), sun_azimuth=1.0, samples=256)
    np.testing.assert_array_equal(L.reshape(-1, 2), ref.radiance)
    sun = sky.sun_spectral_radiance(wl)
    assert sun.shape == (2,) and np.all(sun > 1e3)
    assert np.allclose(sky.sun_direction @ [0, 0, 1], math.cos(math.radians(40.0)))
    with pytest.raises(InvalidParameterError):
        MonteCarloSky(0.5, samples=0)


def test_aerosol_phase_function_comes_from_the_atmosphere():
    """sky_radiance and MonteCarloSky take the aerosol phase function from AtmosphereParameters.mie_phase_function
    (no separate argument); it survives the sky's to_dict/from_dict round trip."""
    from skyscatter.sky.montecarlo import MonteCarloSky
    from skyscatter.sky.registry import from_dict

    hg = EARTH.replace(mie_phase_function="henyey-greenstein")
    kw = dict(sun_zenith=0.7, samples=64, seed=3, scheduler="synchronous")
    a = sky_radiance(hg, DIRS, [550.0], **kw).radiance
    b = sky_radiance(EARTH, DIRS, [550.0], **kw).radiance
    assert not np.any(a == b)
    sky = MonteCarloSky(0.7, atmosphere=hg, samples=64, seed=3, scheduler="synchronous")
    np.testing.assert_array_equal(sky.spectral_radiance(DIRS, [550.0]), a)
    again = from_dict(sky.to_dict())
    assert again.atmosphere.mie_phase_function == "henyey-greenstein"
    with pytest.raises(TypeError):
        sky_radiance(EARTH, DIRS, [550.0], phase="henyey-greenstein", **kw)
