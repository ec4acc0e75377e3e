"""Landscape integration of the precomputed atmosphere (Bruneton & Neyret 2008, Sec. 5, Eqs. 16-18).

Small tables (``sizes=``) keep the precomputation to about a second; the transmittance table is kept at its
default size where a test compares transmittances across wavelengths (its interpolation error is the test's
tolerance).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from skyscatter.aerial.bruneton import BrunetonAerialPerspective, aerial_perspective, transmittance_matrix
from skyscatter.errors import InvalidParameterError
from skyscatter.precomputed import BrunetonSky, PrecomputedAtmosphere  # the old path of BrunetonSky (alias)
from skyscatter.render.camera import PinholeCamera
from skyscatter.render.heightfield import HeightfieldTracer
from skyscatter.render.shafts import shadow_lengths
from skyscatter.render.terrain import Terrain

SIZES = dict(transmittance_mu=256, transmittance_r=64, irradiance_mu_s=16, irradiance_r=8, scattering_r=8,
             scattering_mu=32, scattering_mu_s=8, scattering_nu=4)

# A ridge 200 m high along y on flat ground, top x in [0, 100] m, 10 m cells; the sun in the west.
SPACING = 10.0
RIDGE_TOP, RIDGE_EAST = 200.0, 100.0
SUN_ELEVATION = math.radians(10.0)
SUN = np.array([-math.cos(SUN_ELEVATION), 0.0, math.sin(SUN_ELEVATION)])


@pytest.fixture(scope="module")
def atm():
    return PrecomputedAtmosphere.compute(orders=2, sizes=SIZES, progress=False)


@pytest.fixture(scope="module")
def ridge():
    x = np.arange(-2000.0, 2000.0 + 1, SPACING)
    y = np.arange(-1000.0, 1000.0 + 1, SPACING)
    h = np.zeros((y.size, x.size))
    h[:, (x >= 0) & (x <= RIDGE_EAST)] = RIDGE_TOP
    return HeightfieldTracer(Terrain(h, SPACING, origin=(x[0], y[0]), name="ridge"))


def analytic_shadow(origin, d, s):
    """Shadowed length of the segment [0, s] behind the ridge: points east of its top edge lie in shadow below
    the plane through that edge along the sun, ``z < top - (x - x_e) tan(elevation)``. The plane is crossed
    at most once along a straight ray, so the length follows from one root (exact, independent of the code)."""
    f0 = origin[2] - RIDGE_TOP + (origin[0] - RIDGE_EAST) * math.tan(SUN_ELEVATION)
    df = d[2] + d[0] * math.tan(SUN_ELEVATION)
    # Only rays that stay east of the ridge top are used below, so f < 0 is the shadow condition.
    if df == 0:
        return s if f0 < 0 else 0.0
    root = -f0 / df
    if f0 < 0:
        return float(np.clip(root, 0.0, s)) if df > 0 else s
    return float(s - np.clip(root, 0.0, s)) if df < 0 else 0.0


def test_provider_matches_aerial_perspective(atm):
    rng = np.random.default_rng(5)
    d = rng.normal(size=(300, 3))
    d[:, 2] = np.abs(d[:, 2]) * 0.3 - 0.004  # near-horizontal rays that stay above the sphere within 60 km
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    s = rng.uniform(50.0, 60_000.0, 300)
    sun = np.array([0.3, -0.9, 0.2])
    sun /= np.linalg.norm(sun)
    provider = BrunetonAerialPerspective(atm, sun)
    tau, l_in = provider.evaluate(d, s, 800.0, atm.wavelengths)
    cam = np.array([0.0, 0.0, atm.parameters.bottom_radius + 800.0])
    tau_ref, l_ref = aerial_perspective(cam, cam + s[:, None] * d, sun, atmosphere=atm)
    np.testing.assert_allclose(tau, tau_ref, rtol=1e-12, atol=0)
    np.testing.assert_allclose(l_in, l_ref, rtol=1e-12, atol=0)
    # The protocol's two methods agree with evaluate.
    np.testing.assert_array_equal(provider.transmittance(d, s, 800.0, atm.wavelengths), tau)
    np.testing.assert_array_equal(provider.inscattered(d, s, 800.0, atm.wavelengths), l_in)
    # The same through a BrunetonSky (its sun, its atmosphere).
    sky = BrunetonSky(math.acos(sun[2]), math.atan2(sun[0], sun[1]), precomputed=atm)
    np.testing.assert_allclose(BrunetonAerialPerspective(sky).evaluate(d, s, 800.0, atm.wavelengths)[1], l_ref,
                               rtol=1e-9)


def test_transmittance_at_other_wavelengths(atm):
    """Optical lengths recovered from 3 table wavelengths give the transmittance at others: against tables
    computed directly at those wavelengths (same 256 x 64 transmittance table; tolerance 3e-3 absolute, the
    difference between interpolating T and exp(-tau) in the table)."""
    wl = np.array([400.0, 480.0, 600.0, 720.0])
    other = PrecomputedAtmosphere.compute(orders=1, sizes=SIZES, wavelengths=wl, progress=False)
    rng = np.random.default_rng(2)
    d = rng.normal(size=(200, 3))
    d[:, 2] = np.abs(d[:, 2]) * 0.3 - 0.004
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    s = rng.uniform(100.0, 40_000.0, 200)
    tau = BrunetonAerialPerspective(atm, [0.0, 0.0, 1.0]).transmittance(d, s, 500.0, wl)
    cam = np.array([0.0, 0.0, atm.parameters.bottom_radius + 500.0])
    ref, _ = other.aerial_perspective(cam, cam + s[:, None] * d, [0.0, 0.0, 1.0])
    assert np.max(np.abs(tau - ref)) < 3e-3
    # Exact on the table's own wavelengths for every optical depth the medium can produce: tau(lambda) is
    # beta_R(lambda) L_R + beta_M,ext(lambda) L_M + beta_O3(lambda) L_O3 for path lengths L >= 0.
    p, own = atm.parameters, atm.wavelengths
    basis = np.stack([p.rayleigh_scattering_at(own), p.mie_extinction_at(own), p.ozone_absorption_at(own)], axis=-1)
    depths = basis @ rng.uniform(0.0, 5e4, (3, 10))
    matrix = transmittance_matrix(own, own, p)
    np.testing.assert_allclose(matrix @ depths, depths, rtol=1e-9, atol=1e-12)


def test_shadow_length_zero_without_occluder():
    flat = Terrain(np.zeros((64, 64)), 50.0, wrap=True)
    rng = np.random.default_rng(0)
    d = rng.normal(size=(500, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    origins = np.column_stack([rng.uniform(-1e4, 1e4, 500), rng.uniform(-1e4, 1e4, 500), np.full(500, 100.0)])
    # Rays end on the ground where they meet it, else after up to 20 km of air.
    s = np.minimum(HeightfieldTracer(flat).intersect(origins, d), rng.uniform(0.0, 20_000.0, 500))
    assert np.sum(s < 20_000.0) > 100
    sun = np.array([0.0, -0.5, 0.3])
    np.testing.assert_array_equal(shadow_lengths(flat, origins, d, s, sun), 0.0)


def test_shadow_length_behind_ridge(ridge):
    """Against the analytic length behind a long ridge: within step / 2**(refine + 1) = s / 16384 + 1e-2 m."""
    rng = np.random.default_rng(3)
    cases = []
    for _ in range(200):
        origin = np.array([rng.uniform(300.0, 1500.0), rng.uniform(-200.0, 200.0), rng.uniform(5.0, 300.0)])
        pitch = math.radians(rng.uniform(-12.0, -0.5))
        yaw = math.radians(rng.uniform(-40.0, 40.0))  # looking west, towards the sun and the ridge
        d = np.array([-math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw), math.sin(pitch)])
        s = float(ridge.intersect(origin, d[None])[0])
        if not np.isfinite(s) or origin[0] + s * d[0] <= RIDGE_EAST + SPACING:
            continue  # keep rays that end on the flat ground east of the ridge
        cases.append((origin, d, s))
    assert len(cases) > 40
    for origin, d, s in cases[:40]:
        got = float(shadow_lengths(ridge, origin, d[None], [s], SUN, samples=32, refine=8)[0])
        assert got == pytest.approx(analytic_shadow(origin, d, s), abs=s / 16384 + 1e-2)


def test_shadow_length_sun_below_horizon_and_bad_input(ridge):
    d = np.array([[-1.0, 0.0, -0.05]])
    assert shadow_lengths(ridge, [500.0, 0.0, 50.0], d, [100.0], [-1.0, 0.0, -0.01])[0] == 0.0
    with pytest.raises(InvalidParameterError, match="samples"):
        shadow_lengths(ridge, [500.0, 0.0, 50.0], d, [100.0], SUN, samples=0)
    with pytest.raises(InvalidParameterError, match="distances"):
        shadow_lengths(ridge, [500.0, 0.0, 50.0], d, [np.inf], SUN)
    with pytest.raises(InvalidParameterError, match="camera"):
        BrunetonAerialPerspective(PrecomputedAtmosphere.compute(orders=1, sizes=SIZES, progress=False), SUN,
                                  terrain=ridge).evaluate(d, [100.0], 50.0)


def test_light_shafts_eq17_ground_rays(atm, ridge):
    """Eq. 17: the shadowed length moves to the object's end, so the inscatter is that of the lit length
    s - l alone (checked against aerial_perspective of the shortened ray), 0 for a fully shadowed ray, and
    the transmittance does not change."""
    provider = BrunetonAerialPerspective(atm, SUN, terrain=ridge)
    origin = np.array([1200.0, 0.0, 100.0])
    wl = atm.wavelengths
    cam = np.array([0.0, 0.0, atm.parameters.bottom_radius + origin[2]])
    partial = 0
    for pitch_deg in (-2.0, -3.0, -5.0, -8.0):
        p = math.radians(pitch_deg)
        d = np.array([-math.cos(p), 0.0, math.sin(p)])
        s = float(ridge.intersect(origin, d[None])[0])
        l_exact = analytic_shadow(origin, d, s)
        partial += 0.0 < l_exact < s
        tau, l_in = provider.evaluate_rays(origin, d[None], [s], wl)
        tau0, l_lit = aerial_perspective(cam, cam + (s - l_exact) * d, SUN, atmosphere=atm)
        tau_full, l_full = aerial_perspective(cam, cam + s * d, SUN, atmosphere=atm)
        np.testing.assert_allclose(tau[0], tau_full, rtol=1e-12)
        np.testing.assert_allclose(l_in[0], l_lit, rtol=1e-3)
        assert np.all(l_in[0] <= l_full * (1 + 1e-12))
    assert partial >= 2
    # Camera in the shadow, looking down into it: the whole ray is shadowed and receives no inscatter.
    origin = np.array([300.0, 0.0, 20.0])
    d = np.array([[-0.7, 0.0, -0.2]])
    d /= np.linalg.norm(d)
    s = float(ridge.intersect(origin, d)[0])
    assert analytic_shadow(origin, d[0], s) == s
    tau, l_in = provider.evaluate_rays(origin, d, [s], wl)
    np.testing.assert_array_equal(l_in, 0.0)
    lit_tau, lit_in = BrunetonAerialPerspective(atm, SUN).evaluate_rays(origin, d, [s], wl)
    np.testing.assert_allclose(tau, lit_tau, rtol=1e-12)
    assert np.all(lit_in > 0)


def test_light_shafts_eq18_sky_rays(atm, ridge):
    """Eq. 18: a sky ray from a camera in the ridge's shadow sees T(x, x_s) S|x_s with x_s = x + l v."""
    provider = BrunetonAerialPerspective(atm, SUN, terrain=ridge)
    origin = np.array([300.0, 0.0, 20.0])
    d = np.array([-1.0, 0.0, 1.0]) / math.sqrt(2.0)  # passes 20 m above the ridge top
    assert not np.isfinite(ridge.intersect(origin, d[None])[0])
    l_exact = analytic_shadow(origin, d, 1e5)
    assert 100.0 < l_exact < 400.0
    got = provider.sky_radiance(origin, d[None], atm.wavelengths)[0]
    cam = np.array([0.0, 0.0, atm.parameters.bottom_radius + origin[2]])
    xs = cam + l_exact * d
    tau_s, _ = aerial_perspective(cam, xs, SUN, atmosphere=atm)
    expected = tau_s * atm.sky_radiance(xs, d, SUN)
    np.testing.assert_allclose(got, expected, rtol=1e-3)
    unshadowed = atm.sky_radiance(cam, d, SUN)
    assert np.all(got < unshadowed)


def test_render_with_bruneton_provider(atm, ridge):
    """A 64 x 36 render: finite, non-negative, and the shafts darken the haze (never brighten it)."""
    from skyscatter.render.bruneton import bruneton_scene

    cam = PinholeCamera.from_degrees((900.0, 0.0, 60.0), 270.0, 3.0, 70.0)
    sun_zenith, sun_azimuth = math.pi / 2 - SUN_ELEVATION, math.radians(270.0)
    terrain = ridge.terrain
    with_shafts = bruneton_scene(terrain, cam, sun_zenith, sun_azimuth, precomputed=atm).render(64, 36)
    without = bruneton_scene(terrain, cam, sun_zenith, sun_azimuth, precomputed=atm, shafts=False).render(64, 36)
    for res in (with_shafts, without):
        assert res.rgb.shape == (36, 64, 3)
        assert np.all(np.isfinite(res.rgb)) and np.all(res.rgb >= 0)
    hit = np.isfinite(with_shafts.distance)
    y_with = with_shafts.rgb[..., 1][hit]
    y_without = without.rgb[..., 1][hit]
    assert np.all(y_with <= y_without * (1 + 1e-5) + 1e-9)
    assert np.any(y_with < 0.99 * y_without)
