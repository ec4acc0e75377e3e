"""Forward photons through the spherical atmosphere (skyscatter.montecarlo.sphere) against things they do not share.

* Clear air (Earth defaults, ground albedo 0.2, 550 nm) at sun 30, 10 and 2 deg: the diffuse irradiance of a 0.5 deg
  ring of local sun elevation against backward cosine-weighted paths from the ground
  (:func:`skyscatter.montecarlo.domain.ground_irradiance`: another estimator, no heavy tail in clear air), within 3
  combined standard errors plus the ring's width as a bias bound: the ring's mean over ``sin e`` against the value
  at its centre differs by ``(de)^2 / 24 |E''/E|``, with ``E`` about linear in ``sin e`` over a ring 0.5 deg wide
  (at most 1e-4 relative, from the ``E(e)`` of the backward paths at 1.75, 2 and 2.25 deg: curvature term 0.01 %),
  so the margin is 0.1 %. The direct irradiance against the exact Beer-Lambert transmittance along the sun's chord
  (the column integrator, itself checked against scipy's quadrature in test_montecarlo_physics.py) within 3
  standard errors.
* Energy: no absorption (Rayleigh only, no ozone) over a black ground: every launched photon either reaches the
  ground or leaves through the top (ground + escaped = 1 to rounding; no Russian roulette fires at weight 1).
* The truncation of the launch annulus: a margin of 6 deg instead of the default 3 deg leaves the 10 deg ring's
  diffuse irradiance (450 nm, the most scattering air) within 3 combined standard errors (at 10 deg both edges of
  the annulus move; at 2 deg its outer edge is the top of the atmosphere for either margin). An annulus without
  the rays that cross the air above the ring but land elsewhere is refused (landing elevations 0.75-3.25 deg give
  7 % of the 2 deg ring's sky light, docs/clouds.md).
* The radiance's normalisation (ring area x solid angle x cosine): over bins covering the hemisphere (18 x 6),
  ``sum L_bin * integral of cos over the bin`` is the diffuse irradiance of the same photons, to the bins' finite
  size (the radiance's variation across a 5 deg bin: 0.5 % allowed, a factor 2 in the solid angle would be 50 %).
* The same bits on the synchronous and the threaded scheduler.
* Clear errors on bad input.

The cloud layers' references and the cloudy sky against them: benchmarks/cloudy_sphere_reference.py,
tests/test_cloudy_sphere.py (docs/clouds.md, "Forward photons in the sphere").
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.errors import InvalidParameterError
from skyscatter.montecarlo.domain import ground_irradiance
from skyscatter.montecarlo.sphere import sphere_direct_irradiance, sphere_ground_fluxes

EARTH = AtmosphereParameters(ground_albedo=0.2)
HALF = math.radians(0.25)
#: the ring's width as a bias bound (module docstring)
RING_MARGIN = 0.001


def _ring(e_deg: float) -> np.ndarray:
    return np.array([math.radians(e_deg) - HALF, math.radians(e_deg) + HALF])


@pytest.mark.slow
@pytest.mark.parametrize("sun, photons", [(30.0, 400_000), (10.0, 600_000), (2.0, 1_500_000)])
def test_clear_air_against_backward_paths_and_beer_lambert(sun, photons):
    fwd = sphere_ground_fluxes(EARTH, [550.0], elevation_edges=_ring(sun), photons=photons, seed=7)
    bwd = ground_irradiance(EARTH, [550.0], sun_zenith=math.radians(90.0 - sun), samples=6000, seed=8)
    f, fe = fwd.diffuse[0, 0], fwd.diffuse_stderr[0, 0]
    b, be = bwd.diffuse[0, 0], bwd.diffuse_stderr[0, 0]
    assert fe < 0.03 * f
    assert abs(f - b) <= 3.0 * math.hypot(fe, be) + RING_MARGIN * b, (f, fe, b, be)
    exact = sphere_direct_irradiance(EARTH, [550.0], _ring(sun))[0, 0]
    assert abs(fwd.direct[0, 0] - exact) <= 3.0 * fwd.direct_stderr[0, 0], (fwd.direct[0, 0], exact)


def test_energy_without_absorption_over_a_black_ground():
    atm = AtmosphereParameters(ground_albedo=0.0, mie_angstrom_beta=0.0, ozone_column=0.0)
    r = sphere_ground_fluxes(atm, [450.0], elevation_edges=np.radians([-5.0, 90.0]), photons=8192, seed=3)
    assert r.launch[0] < 1e-6 * atm.bottom_radius and r.launch[1] == atm.top_radius
    np.testing.assert_allclose(r.ground_fraction + r.escaped_fraction, 1.0, rtol=0, atol=1e-9)
    assert r.absorbed_fraction[0] == 0.0
    # most of the light reaches the ground, some is scattered back out
    assert 0.5 < r.ground_fraction[0] < 1.0 and r.escaped_fraction[0] > 0.02


@pytest.mark.slow
def test_launch_annulus_truncation_costs_nothing():
    ring = _ring(10.0)
    a = sphere_ground_fluxes(EARTH, [450.0], elevation_edges=ring, photons=600_000, seed=11)
    b = sphere_ground_fluxes(EARTH, [450.0], elevation_edges=ring, photons=600_000, seed=12,
                             margin=math.radians(6.0))
    assert b.launch[0] < a.launch[0] and b.launch[1] > a.launch[1]
    d, s = a.diffuse[0, 0] - b.diffuse[0, 0], math.hypot(a.diffuse_stderr[0, 0], b.diffuse_stderr[0, 0])
    assert s < 0.02 * a.diffuse[0, 0]
    assert abs(d) <= 3.0 * s, (a.diffuse, b.diffuse, s)


def test_rays_that_land_elsewhere_carry_the_low_suns_sky_light():
    ring = _ring(2.0)
    rb = EARTH.bottom_radius
    kw = dict(elevation_edges=ring, photons=100_000, seed=13)
    full = sphere_ground_fluxes(EARTH, [450.0], **kw)
    with pytest.raises(InvalidParameterError, match="every ray through the air"):
        sphere_ground_fluxes(EARTH, [450.0], launch=[rb * math.cos(math.radians(3.25)),
                                                     rb * math.cos(math.radians(0.75))], **kw)
    assert full.launch[1] == EARTH.top_radius
    assert full.diffuse_stderr[0, 0] < 0.05 * full.diffuse[0, 0]


def test_radiance_integrates_to_the_diffuse_irradiance():
    zen = np.radians(np.arange(0.0, 90.1, 5.0))
    r = sphere_ground_fluxes(EARTH, [550.0], elevation_edges=_ring(30.0), photons=100_000, seed=9,
                             view_zenith_edges=zen, azimuth_bins=6)
    # integral of cos over a bin: 2 dphi (sin^2 z1 - sin^2 z0) / 2 (both sides of the sun's plane)
    dphi = math.pi / 6
    cos_int = dphi * (np.sin(zen[1:]) ** 2 - np.sin(zen[:-1]) ** 2)
    e = float(np.sum(r.radiance[0, :, :, 0] * cos_int[:, None]))
    assert e == pytest.approx(r.diffuse[0, 0], rel=0.005)


def test_same_bits_on_any_local_scheduler():
    kw = dict(elevation_edges=_ring(10.0), photons=4096, seed=5, view_zenith_edges=np.radians([0, 45, 90]),
              azimuth_bins=2)
    a = sphere_ground_fluxes(EARTH, [450.0, 650.0], scheduler="synchronous", **kw)
    b = sphere_ground_fluxes(EARTH, [450.0, 650.0], scheduler="threads", **kw)
    for name in ("direct", "diffuse", "diffuse_stderr", "radiance", "ground_fraction", "escaped_fraction"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.radiance.shape == (1, 2, 2, 2) and np.all(a.radiance >= 0)


@pytest.mark.parametrize("kw, match", [
    (dict(photons=0), "photons"),
    (dict(photons=100), "photons"),
    (dict(elevation_edges=[0.1]), "elevation_edges"),
    (dict(elevation_edges=[0.2, 0.1]), "elevation_edges"),
    (dict(elevation_edges=[0.1, 2.0]), "elevation_edges"),
    (dict(launch=[6.35e6, 6.4e6]), "every ray through the air"),
    (dict(launch=[5.0e6, 6.3e6]), "every ray through the air"),
    (dict(launch=[5.0e6, 7.0e6]), "impact parameters"),
    (dict(launch=[6.0e6, 5.0e6]), "impact parameters"),
    (dict(elevation_edges=[-0.05, -0.01]), "sunlit ground"),
    (dict(margin=-0.1), "margin"),
    (dict(view_zenith_edges=[0.0, 2.0]), "view_zenith_edges"),
    (dict(azimuth_bins=0), "azimuth_bins"),
    (dict(wavelengths=[-5.0]), "wavelength"),
])
def test_bad_input_is_refused(kw, match):
    args = dict(wavelengths=[550.0], elevation_edges=[0.1, 0.11], photons=4096)
    args.update(kw)
    wl = args.pop("wavelengths")
    with pytest.raises(InvalidParameterError, match=match):
        sphere_ground_fluxes(EARTH, wl, **args)
