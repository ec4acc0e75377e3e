"""The ``broken-cloud`` sky's ground irradiance (BrokenCloudSky.ground_irradiance, domain_ground_irradiance) and its
view from above, against the clear-sky tables, an analytic chord and stored Monte Carlo values
(tests/data/broken_cloud_domain_montecarlo.json and broken_cloud_above_montecarlo.npz, written with their seeds by
benchmarks/broken_cloud_domain_montecarlo.py; the figures in docs/clouds.md by benchmarks/broken_cloud_accuracy.py)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.atmosphere.clouds import CloudField, CloudLayer
from skyscatter.errors import InvalidParameterError
from skyscatter.sky.broken_cloud import BrokenCloudSky

DATA = Path(__file__).parent / "data"
IRRADIANCE = DATA / "broken_cloud_domain_montecarlo.json"
ABOVE = DATA / "broken_cloud_above_montecarlo.npz"
DROPS = CloudLayer(0.0, 1.0, 1.0, effective_radius=10e-6)  # the droplets' optics only
SUN_Z, SUN_A = math.radians(50.0), math.radians(135.0)
WL = np.array([450.0, 550.0, 650.0])


def _field(cover: float, scene: dict) -> CloudField:
    """The procedural field of the stored scene (as benchmarks/broken_cloud_montecarlo.py's ``field_for``)."""
    drops = CloudLayer(0.0, 1.0, 1.0, effective_radius=scene["effective_radius"])
    return CloudField.procedural(cover=cover, base=scene["base"], top=scene["top"], particles=drops,
                                 optical_depth=scene["optical_depth"], size=scene["size"],
                                 resolution=tuple(scene["resolution"]), feature_size=scene["feature_size"],
                                 seed=scene["field_seed"])


def test_empty_field_ground_irradiance_is_the_tables():
    """No cloud: the direct part is the tables' sun term and the diffuse part the tables' sky irradiance (the
    quadrature only integrates the cloud's change), at any point of the domain."""
    sky = BrokenCloudSky(SUN_Z, SUN_A, clouds=CloudField(np.zeros((4, 4, 2)), 8000.0, 1000.0, 2000.0, DROPS))
    tab = sky._tables
    pts = np.array([[0.0, 0.0], [3000.0, -2500.0]])
    direct, diffuse = sky.ground_irradiance(pts, tab.wavelengths, zeniths=4, azimuths=8)
    bottom = tab.parameters.bottom_radius
    g = np.stack([pts[:, 0], pts[:, 1], np.sqrt(bottom**2 - (pts**2).sum(axis=1))], axis=-1)
    e_sun, e_sky = tab.ground_irradiance(g, g / bottom, sky.sun_direction)
    np.testing.assert_allclose(direct, tab.resample(e_sun, tab.wavelengths), rtol=1e-12)
    np.testing.assert_allclose(diffuse, tab.resample(e_sky, tab.wavelengths), rtol=1e-12)


#: The march's step error in the diffuse part between points of a uniform 8 x 8 x 8-voxel layer (see below;
#: measured 0.36-0.43 % at 450-650 nm; the march is deterministic).
RTOL_MARCH = 5e-3


def test_uniform_layer_direct_is_the_slant_chord_and_the_diffuse_moves_with_the_cloud():
    """Under a uniform layer the direct part is the clear sky's times ``exp(-sigma k chord)`` along the spherical
    chord to the sun (exact, 1e-9); the diffuse part is finite, positive and not the clear sky's; the domain
    mean of a uniform layer is a single point's (translation invariance), the direct part to 1e-7 (the ground's
    curvature), the diffuse part to :data:`RTOL_MARCH` (the march's midpoint steps of half a voxel fall differently
    from each point; with one 1 km voxel the points differed by 2.5 %)."""
    tau = 1.5
    ext = tau / 500.0
    sky = BrokenCloudSky(SUN_Z, SUN_A, clouds=CloudField(np.full((8, 8, 8), ext), 1000.0, 1000.0, 1500.0, DROPS),
                         interpolation="voxel")
    clear = BrokenCloudSky(SUN_Z, SUN_A, clouds=CloudField(np.zeros((1, 1, 1)), 1000.0, 1000.0, 1500.0, DROPS))
    bottom = sky._tables.parameters.bottom_radius
    mu = math.cos(SUN_Z)

    def t(r):
        return -bottom * mu + math.sqrt(r * r - bottom * bottom * (1.0 - mu * mu))

    chord = t(bottom + 1500.0) - t(bottom + 1000.0)
    k = DROPS.extinction_at(WL) / DROPS.extinction_at([550.0])[0]
    d0, f0 = clear.ground_irradiance(None, WL, zeniths=4, azimuths=8)
    d1, f1 = sky.ground_irradiance(None, WL, zeniths=4, azimuths=8)
    np.testing.assert_allclose(d1[0], d0[0] * np.exp(-ext * chord * k), rtol=1e-9)
    assert np.all(np.isfinite(f1)) and np.all(f1 > 0.0) and np.all(np.abs(f1 / f0 - 1.0) > 0.01)
    dm, fm = sky.domain_ground_irradiance(WL, points_per_axis=2, direct_points=2, zeniths=4, azimuths=8)
    # the points 250 m from the foot point stand on the curved ground: their sun is 4e-5 rad higher or lower
    # (measured 2e-9 in the direct part)
    np.testing.assert_allclose(dm, d1[0], rtol=1e-7)
    # the diffuse part through the march, whose midpoint steps (half a voxel) fall differently from each point
    np.testing.assert_allclose(fm, f1[0], rtol=RTOL_MARCH)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"points": [1.0, 2.0, 3.0]}, "points"),
    ({"points": [[np.nan, 0.0]]}, "points"),
    ({"zeniths": 0}, "zeniths"),
    ({"azimuths": 1.5}, "azimuths"),
])
def test_bad_ground_irradiance_input_is_refused(kwargs, match):
    sky = BrokenCloudSky(SUN_Z, SUN_A, clouds=CloudField(np.zeros((2, 2, 1)), 2000.0, 1000.0, 2000.0, DROPS))
    with pytest.raises(InvalidParameterError, match=match):
        sky.ground_irradiance(**kwargs)


def test_ground_cloud_coupling_against_disort(monkeypatch):
    """The ground's light on the cloud bases (``BrokenCloudSky._ground_up``): under a uniform layer of optical depth
    15 (1000-1500 m, sun 30 deg from the zenith) the diffuse ground irradiance grows with the ground albedo by the
    bounces between ground and base; its ratio between albedo 0.6 and 0 against the DISORT ``cloudy`` model's
    (an independent plane-parallel solution with a Lambertian ground), 450 / 550 / 650 nm. Measured 1.667 / 1.616 /
    1.594 against DISORT's 1.610 / 1.600 / 1.595 (+3.5 / +1.0 / -0.1 %) since the cloud-top-air coupling (the air
    above sending back the layer's light; without it 1.803 / 1.688 / 1.635, +12 / +5.5 / +2.5 %: over the dark
    ground the model's sky lacked the air's return of the cloud's light, while the tables of the bright ground
    held its return of the ground's light); before the ground coupling (the ground sending up the clear sky's
    light) 1.382 / 1.187 / 1.103 (-14 to -31 %). Tolerance 15 %. (Optical depth 5: 1.300 / 1.276 / 1.266 against
    1.344 / 1.313 / 1.300.)

    The clear-sky tables of both models at the sizes of CloudySky's own coupling tables
    (``skyscatter.sky.cloudy.COUPLING_TABLE_SIZES``) instead of the default ones: the ratio does not depend on them
    (the same 1.667 / 1.616 / 1.594 at both sizes, 2026-12-03), and the two models then share one table build per
    albedo (2 builds instead of 4: 30 s of CPU instead of 120)."""
    pytest.importorskip("disortpp")
    import skyscatter.precomputed.cache as cache
    from skyscatter.sky.cloudy import COUPLING_TABLE_SIZES, CloudySky

    real = cache.load_or_compute

    def coupling_sizes(atmosphere=None, **kwargs):
        if kwargs.get("sizes") is None:
            kwargs["sizes"] = COUPLING_TABLE_SIZES
        return real(atmosphere, **kwargs)

    monkeypatch.setattr(cache, "load_or_compute", coupling_sizes)

    sz = math.radians(30.0)
    field = CloudField(np.full((1, 1, 8), 15.0 / 500.0), 1000.0, 1000.0, 1500.0, DROPS)
    model, disort = [], []
    for rho in (0.0, 0.6):
        sky = BrokenCloudSky(sz, 0.0, clouds=field, atmosphere=AtmosphereParameters(ground_albedo=rho),
                             interpolation="voxel")
        model.append(sky.ground_irradiance(None, WL, zeniths=16, azimuths=32)[1][0])
        disort.append(CloudySky(sz, 0.0, cloud_optical_depth=15.0, cloud_base=1000.0, cloud_top=1500.0,
                                ground_albedo=rho).diffuse_fluxes(WL)[0])
    np.testing.assert_allclose(model[1] / model[0], disort[1] / disort[0], rtol=0.15)


def test_ground_coupling_is_self_consistent():
    """The coupling's upward irradiance is the ground albedo times the domain-mean global irradiance the model then
    gives (``E_up = rho (E_dir + E_dif)``, solved on 4 x 4 points x 8 x 16 directions; checked here on 8 x 8
    points x 16 x 32 directions), cover 0.9, sun 60 deg high, within 3 % (the two quadratures)."""
    mc = json.loads(IRRADIANCE.read_text())
    scene = mc["scene"]
    air = AtmosphereParameters(ground_albedo=scene["ground_albedo"])
    sky = BrokenCloudSky(math.radians(30.0), math.radians(scene["sun_azimuth_deg"]), clouds=_field(0.9, scene),
                         atmosphere=air, interpolation="voxel")
    wl = sky._tables.wavelengths
    direct, diffuse = sky.domain_ground_irradiance(wl, points_per_axis=8, zeniths=16, azimuths=32)
    np.testing.assert_allclose(sky._ground_up["e_up"], scene["ground_albedo"] * (direct + diffuse), rtol=0.03)


def _cases():
    return list(json.loads(IRRADIANCE.read_text())["cases"])


#: The issue's target for the domain-mean ground irradiance (direct + diffuse).
GLOBAL_TOLERANCE = 0.05
@pytest.mark.parametrize("key", _cases())
def test_domain_mean_ground_irradiance_against_the_monte_carlo(key):
    """Domain-mean ground irradiance / (mu0 F0) against the forward photons' (196608 photons, standard errors
    0.25-0.4 %; seeds in the JSON), covers 0.3 / 0.6 / 0.9, sun 30 and 60 deg high: the direct part within 1 %
    (both exact through the same voxels; measured -0.04 to -0.4 %: the tables' clear-air transmittance against
    the Monte Carlo's), direct + diffuse within :data:`GLOBAL_TOLERANCE` (the issue's 5 %). Cover 0.9 / sun 60 deg
    was a strict expected failure until 2026-12-04: 0.866 / 0.863 / 0.865 at 450 / 550 / 650 nm before the
    couplings, 0.934 / 0.935 / 0.939 with them, 0.948 / 0.948 / 0.952 with the convolved octave phases; with the
    diffusion's profile near the cloud base (``BASE_PROFILE``: the base's light limb-darkened, its flux no longer
    spread evenly over the elevations) IRRFIG (docs/clouds.md)."""
    mc = json.loads(IRRADIANCE.read_text())
    scene, case = mc["scene"], mc["cases"][key]
    zen = math.radians(90.0 - case["sun_elevation_deg"])
    air = AtmosphereParameters(ground_albedo=scene["ground_albedo"])
    sky = BrokenCloudSky(zen, math.radians(scene["sun_azimuth_deg"]), clouds=_field(case["cover"], scene),
                         atmosphere=air, interpolation="voxel")
    direct, diffuse = sky.domain_ground_irradiance(WL, points_per_axis=4, zeniths=16, azimuths=32)
    norm = math.cos(zen) * np.asarray(air.solar_irradiance_at(WL), dtype=float)
    np.testing.assert_allclose(direct / norm, case["direct"], rtol=0.01)
    ratio = (direct + diffuse) / norm / np.asarray(case["global"])
    assert np.all(np.abs(ratio - 1.0) < GLOBAL_TOLERANCE), ratio


#: The view from above, measured (docs/clouds.md; merged tree 58cef41): disc means 0.83-0.92 of the Monte Carlo's,
#: per-pixel RMS 0.19-0.36 (the Monte Carlo's own median relative standard error per pixel 6-9 %). Regression guards.
MEAN_ABOVE = 0.22
RMS_ABOVE = 0.40


@pytest.mark.parametrize("index", [0, 1, 2])
def test_view_from_above_against_the_monte_carlo(index):
    """Nadir fisheye from 10 km (32 x 32, 812 pixels, 1024 paths per pixel, seeds in the file), covers 0.3 / 0.6 /
    0.9, 450 / 550 / 650 nm. Tolerances are the measured accuracy as a regression guard (docs/clouds.md): the
    disc mean within MEAN_ABOVE of the Monte Carlo's, per-pixel RMS of the relative difference below RMS_ABOVE."""
    data = np.load(ABOVE)
    meta = json.loads(str(data["meta"]))
    cover = float(data["covers"][index])
    sky = BrokenCloudSky(math.radians(meta["sun_zenith_deg"]), math.radians(meta["sun_azimuth_deg"]),
                         clouds=_field(cover, meta), atmosphere=AtmosphereParameters(
                             ground_albedo=meta["ground_albedo"]), altitude=meta["altitude"], interpolation="voxel")
    mc = data[f"radiance_{index}"]
    model = sky.spectral_radiance(data["directions"], data["wavelengths"])
    ratio = model.mean(axis=0) / mc.mean(axis=0)
    assert np.all(np.abs(ratio - 1.0) < MEAN_ABOVE), ratio
    rel = model / mc - 1.0
    assert np.all(np.sqrt(np.mean(rel**2, axis=0)) < RMS_ABOVE)


def test_air_spherical_albedo_against_the_rayleigh_formula():
    """``air_spherical_albedo`` (DISORT on the reversed air column, the cloud-top-air coupling's ``s``) of a pure
    molecular air (no aerosol, no ozone) above 0 and 2500 m against the spherical albedo of a Rayleigh layer of
    optical depth ``tau``, ``s = (3 tau - E_3(tau) (4 + 2 tau) + 2 exp(-tau)) / (4 + 3 tau)`` (Vermote & Tanre
    1992, JQSRT 47, 305, the formula of 6S's CSALBR; ``E_3`` the exponential integral), 400-700 nm (``tau``
    0.39-0.03). Measured +0.2 to +1.3 % (the largest at 400 nm, optical depth 0.39, where the formula is least
    exact). Tolerance 2 %."""
    pytest.importorskip("disortpp")
    from scipy.special import expn

    from skyscatter.sky.cloudy import air_spherical_albedo

    air = AtmosphereParameters(mie_angstrom_beta=0.0, ozone_column=0.0)
    wl = np.array([400.0, 450.0, 550.0, 700.0])
    for h in (0.0, 2500.0):
        tau = air.rayleigh_scattering_at(wl) * 8000.0 * math.exp(-h / 8000.0)
        # the exponential profile's column above h up to the atmosphere's top
        tau = tau * (1.0 - math.exp(-(air.thickness - h) / 8000.0))
        formula = (3.0 * tau - expn(3, tau) * (4.0 + 2.0 * tau) + 2.0 * np.exp(-tau)) / (4.0 + 3.0 * tau)
        got = air_spherical_albedo(air, wl, h)
        np.testing.assert_allclose(got, formula, rtol=0.02)
