"""The cloudy sky (skyscatter.sky.cloudy.CloudySky) against the Monte Carlo reference and against itself.

* Diffuse irradiance on the ground under water cloud layers of optical depth 1 to 60 (Mie droplets 10 um, 1000-1500
  m, Earth air, ground albedo 0.2, 450 / 550 / 650 nm) against the Monte Carlo's forward photons stored in
  tests/data/cloudy_montecarlo.json (written by benchmarks/cloudy_montecarlo_reference.py, which records the seed
  and the photon counts): within 3 % (the target of docs/clouds.md) plus 3 Monte Carlo standard errors.
* The machinery without a cloud (directions, azimuths from the sun, wavelength interpolation, the layers of the
  air) against the Monte Carlo's clear-sky radiances in the same file (spherical atmosphere): within 3 % plus 3
  standard errors 30 deg or more above the horizon, 5 % at 10 deg (the plane-parallel column's curvature error).
* Low suns: at 10 deg against forward photons (tests/data/cloudy_low_sun.json, two seeds), at 2 deg against 400000
  backward paths; DISORT's cloud under a grazing sun against forward photons in the plane-parallel limit (a
  planet of 1000 Earth radii), where the backward estimate's heavy tail (the old "red excess") shows.
* Self-consistency: the radiance integrated over the upper hemisphere is DISORT's diffuse flux (within 1 %: the
  grid's bilinear interpolation); symmetry about the sun's vertical plane; the solar disc attenuated by
  ``exp(-tau_slant)``; xyz equal to the integrated spectrum; one clear error per bad option.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.errors import InvalidParameterError
from skyscatter.sky import registry
from skyscatter.sky.cloudy import CloudySky

pytest.importorskip("disortpp")

DATA = json.loads((Path(__file__).parent / "data" / "cloudy_montecarlo.json").read_text())
WL = DATA["wavelengths_nm"]


def _case(tau: float, sun: float) -> dict:
    for c in DATA["cases"]:
        if c["tau"] == tau and c["sun_elevation_deg"] == sun:
            return c
    raise KeyError((tau, sun))


def _sky(tau: float, sun: float, **kw) -> CloudySky:
    return CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=DATA["cloud_base_m"],
                     cloud_top=DATA["cloud_top_m"], ground_albedo=DATA["ground_albedo"], **kw)


def _dirs(views):
    return np.array([[math.cos(math.radians(h)) * math.sin(math.radians(a)),
                      math.cos(math.radians(h)) * math.cos(math.radians(a)), math.sin(math.radians(h))]
                     for h, a in views])


@pytest.mark.parametrize("tau, sun", [(1.0, 60.0), (15.0, 60.0), (60.0, 60.0), (5.0, 30.0)])
def test_diffuse_irradiance_against_the_monte_carlo(tau, sun):
    """High suns, forward photons: within 3 % plus 3 standard errors (docs/clouds.md)."""
    case = _case(tau, sun)
    model = _sky(tau, sun).diffuse_fluxes(WL)[0]
    mc = np.array(case["diffuse_irradiance"])
    err = np.array(case["diffuse_irradiance_stderr"])
    assert np.all(np.abs(model - mc) <= 0.03 * mc + 3.0 * err), (model / mc - 1, err / mc)


def test_diffuse_irradiance_at_sunset_against_the_monte_carlo():
    """Sun 2 deg high, Earth radius, against the stored backward paths (20000): the coupling with the spherical
    tables is within 5 % + 3 sigma at 450 nm, where the sky's light on the cloud top dominates; at 650 nm the
    backward estimate is too low (its heavy tail, below), so only the sign and the plane-parallel column's
    failure are checked there (the column alone is 31-35 % too dark at 450-550 nm)."""
    case = _case(15.0, 2.0)
    model = _sky(15.0, 2.0).diffuse_fluxes(WL)[0]
    mc = np.array(case["diffuse_irradiance_backward"])
    err = np.array(case["diffuse_irradiance_backward_stderr"])
    assert abs(model[0] - mc[0]) <= 0.05 * mc[0] + 3.0 * err[0]
    assert np.all(model / mc - 1 > -0.05)
    column = _sky(15.0, 2.0, illumination="column").diffuse_fluxes(WL)[0]
    assert np.all(np.abs(model / mc - 1)[:2] < np.abs(column / mc - 1)[:2])


@pytest.mark.parametrize("tau", [1.0, 5.0])
def test_sun_2_deg_against_400000_backward_paths(tau):
    """Sun 2 deg, Earth radius, against 400000 backward paths (seed 41; docs/clouds.md: 20000 were too few where
    the sun lights the cloud top, 13 % low at 650 nm): 3 % + 3 sigma (measured -2.2 / -5.7 / -2.6 % and -3.7 /
    -11.4 / -9.0 %, standard errors 0.5-6.3 %; those of the red are themselves uncertain)."""
    case = _case(tau, 2.0)
    assert case["backward_paths"] >= 400000
    model = _sky(tau, 2.0).diffuse_fluxes(WL)[0]
    mc = np.array(case["diffuse_irradiance_backward"])
    err = np.array(case["diffuse_irradiance_backward_stderr"])
    assert np.all(np.abs(model - mc) <= 0.03 * mc + 3.0 * err), (model / mc - 1, err / mc)


LOW_SUN = json.loads((Path(__file__).parent / "data" / "cloudy_low_sun.json").read_text())


def _forward_mean(case: dict) -> tuple[np.ndarray, np.ndarray]:
    """Mean of a case's independent forward-photon runs and its standard error."""
    vals = np.array([r["diffuse_irradiance"] for r in case["forward"]])
    errs = np.array([r["diffuse_irradiance_stderr"] for r in case["forward"]])
    return vals.mean(axis=0), np.sqrt((errs ** 2).sum(axis=0)) / len(vals)


def _low_sun_case(tau: float, sun: float, scale: float) -> dict:
    return next(c for c in LOW_SUN["cases"] if (c["air"], c["tau"], c["sun_elevation_deg"], c["radius_scale"])
                == ("earth", tau, sun, scale))


def _scaled_air(scale: float) -> AtmosphereParameters:
    rb = AtmosphereParameters().bottom_radius * scale
    return AtmosphereParameters(bottom_radius=rb, top_radius=rb + AtmosphereParameters().thickness,
                                ground_albedo=LOW_SUN["ground_albedo"])


TOP_SKY = json.loads((Path(__file__).parent / "data" / "cloudy_top_sky.json").read_text())


def _top_sky_case(sun: float) -> tuple[dict, np.ndarray, np.ndarray, np.ndarray]:
    """A case of tests/data/cloudy_top_sky.json, its nodes' cosines and weights and azimuths [rad]."""
    case = next(c for c in TOP_SKY["cases"] if c["sun_elevation_deg"] == sun)
    return (case, np.array(TOP_SKY["mu_nodes"]), np.array(TOP_SKY["mu_weights"]),
            np.radians(np.array(TOP_SKY["azimuths_deg"])))


@pytest.mark.parametrize("sun", [10.0, 2.0])
def test_tables_sky_on_the_cloud_top_against_backward_paths(sun):
    """The clear sky that lights the cloud top (the coupling tables' radiance at 1500 m, the Earth's radius, the
    Earth air, ground albedo 0.2) against backward Monte Carlo paths there, exact in the spherical atmosphere
    (tests/data/cloudy_top_sky.json, benchmarks/cloudy_top_sky_reference.py: 40000 paths per direction, 8 cosines
    x 13 azimuths). Its irradiance (the hemisphere integral) within 2 % + 3 sigma (measured -0.3..-0.9 % at sun
    10 deg, -0.5..-1.8 % at 2 deg), the azimuthal mean at each cosine within 2.5 % (measured up to 1.2 / 2.1 %),
    each direction within 5 % (up to 2.3 / 4.6 %)."""
    case, mu, w, az = _top_sky_case(sun)
    wl = np.array(TOP_SKY["wavelengths_nm"])
    mc = np.array(case["backward"]["radiance"])
    err = np.array(case["backward"]["radiance_stderr"])
    sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=15.0, cloud_base=1000.0,
                    cloud_top=TOP_SKY["cloud_top_m"], ground_albedo=TOP_SKY["ground_albedo"])
    table = sky._table_sky(wl, TOP_SKY["cloud_top_m"], np.arccos(mu), az)
    _, iso = sky._table_illumination(wl, TOP_SKY["cloud_top_m"])
    trap = np.full(az.size, az[1] - az[0])
    trap[[0, -1]] *= 0.5
    e_mc = 2.0 * np.einsum("i,j,ijk->k", mu * w, trap, mc)
    e_err = 2.0 * np.sqrt(np.einsum("i,j,ijk->k", (mu * w) ** 2, trap ** 2, err ** 2))
    assert np.all(np.abs(math.pi * iso - e_mc) <= 0.02 * e_mc + 3.0 * e_err), (math.pi * iso / e_mc - 1)
    ring_mc, ring = np.einsum("j,ijk->ik", trap, mc), np.einsum("j,ijk->ik", trap, table)
    assert np.max(np.abs(ring / ring_mc - 1.0)) < 0.025, np.max(np.abs(ring / ring_mc - 1.0))
    assert np.max(np.abs(table / mc - 1.0)) < 0.05, np.max(np.abs(table / mc - 1.0))


@pytest.mark.parametrize("sun", [10.0, 2.0])
def test_a_vanishing_cloud_gives_the_clear_sky_on_its_top(sun):
    """The adding method's light on the cloud top (``CloudySky._interreflection``) takes out of the tables' sky the
    light that the clear air below the top and the ground sent up (``CloudySky._clear_below``) before it adds the
    cloud's, so under a vanishing cloud the diffuse light on the top is the clear sky's: the tables' irradiance there
    within 0.5 % (the model reads its 17 grid wavelengths; measured 0.0-0.2 %), itself within 2 % of backward Monte
    Carlo paths (:func:`test_tables_sky_on_the_cloud_top_against_backward_paths`). Until 2026-12-04 only the
    ground's albedo was taken out: +2.8 / +2.2 / +1.9 % at 450 / 550 / 650 nm with the sun 10 deg high (+1.2 / +1.2
    / +1.5 % at 2 deg; the air below 1500 m and the ground reflect 0.26 / 0.24 / 0.22 of the light there, mostly at
    low elevations, which the air above returns more than Lambertian light), so the light on a cloud's top was 1.5
    / 0.6 / 0.3 % too bright and the ground under optical depths 15-60 1.8-1.9 % too bright at 450 nm."""
    case, mu, w, az = _top_sky_case(sun)
    wl = np.array(TOP_SKY["wavelengths_nm"])
    kw = dict(cloud_base=1000.0, cloud_top=TOP_SKY["cloud_top_m"], ground_albedo=TOP_SKY["ground_albedo"])
    thin = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=1e-4, altitude=TOP_SKY["cloud_top_m"],
                     **kw)
    down = thin.diffuse_fluxes(wl)[0] / thin.atmosphere.solar_irradiance_at(wl)
    _, iso = thin._table_illumination(wl, TOP_SKY["cloud_top_m"])
    assert np.max(np.abs(down / (math.pi * iso) - 1.0)) < 0.005, down / (math.pi * iso) - 1.0


@pytest.mark.parametrize("tau, sun", [(1.0, 2.0), (15.0, 2.0), (1.0, 10.0), (15.0, 10.0)])
def test_grazing_sun_on_the_cloud_in_the_plane_parallel_limit(tau, sun):
    """DISORT's cloud lit by a grazing sun is right: on a planet of 1000 Earth radii (the same air; the
    plane-parallel limit, where the forward photons' periodic domain is exact and the column's DISORT is the
    whole physics) the column (``illumination="column"``) is within 3 % + 3 sigma of forward photons
    (tests/data/cloudy_low_sun.json: two seeds of 65536 photons, benchmarks/cloudy_low_sun_reference.py;
    measured -2.9 to +1.8 %). The backward paths that gave the old 2-deg table its +20-50 % red excess are
    heavy-tailed there (docs/clouds.md): the reference, not the cloud, was wrong."""
    mc, err = _forward_mean(_low_sun_case(tau, sun, 1000.0))
    sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=LOW_SUN["cloud_base_m"],
                    cloud_top=LOW_SUN["cloud_top_m"], ground_albedo=LOW_SUN["ground_albedo"],
                    atmosphere=_scaled_air(1000.0), illumination="column")
    model = sky.diffuse_fluxes(LOW_SUN["wavelengths_nm"])[0]
    assert np.all(np.abs(model - mc) <= 0.03 * mc + 3.0 * err), (model / mc - 1, err / mc)


@pytest.mark.parametrize("tau", [1.0, 15.0])
def test_sun_10_deg_against_forward_photons(tau):
    """Sun 10 deg, Earth radius, the default coupling with the tables against forward photons (two seeds of
    65536; under these layers the periodic domain's term is at most 1.6 %: the same photons on planets of 1, 4
    and 1000 Earth radii): 3 % + 3 sigma. The clear sky lit the cloud top as an isotropic radiance until
    2026-12-02; its light comes from low elevations, which the cloud passes less: optical depth 15 was then
    +7.1 / +4.1 / +4.6 % (fails), now +1.1 / -0.9 / +1.1 %."""
    mc, err = _forward_mean(_low_sun_case(tau, 10.0, 1.0))
    model = _sky(tau, 10.0).diffuse_fluxes(LOW_SUN["wavelengths_nm"])[0]
    assert np.all(np.abs(model - mc) <= 0.03 * mc + 3.0 * err), (model / mc - 1, err / mc)


def test_clear_sky_radiance_against_the_monte_carlo():
    case = _case(0.0, 30.0)
    sky = _sky(0.0, 30.0)
    model = sky.spectral_radiance(_dirs(case["views_deg"]), WL)
    mc = np.array(case["radiance"])
    err = np.array(case["radiance_stderr"])
    # 5 % (the target of docs/clouds.md) 10 deg above the horizon, where the plane-parallel column's
    # missing curvature is 2-4 % (measured: +3.8 % at 650 nm); 3 % higher up
    allowed = np.array([0.05 if h < 30.0 else 0.03 for h, _ in case["views_deg"]])[:, None]
    assert np.all(np.abs(model - mc) <= allowed * mc + 3.0 * err), (model / mc - 1, err / mc)


@pytest.mark.parametrize("tau", [1.0, 15.0])
def test_hemisphere_integral_is_the_diffuse_flux(tau):
    """The grid as the lookup reads it integrates to DISORT's diffuse flux (the forward peak's light restored
    about the sun: without it 75 % under optical depth 1), on a quadrature other than the restoration's."""
    sky = _sky(tau, 40.0)
    n_t, n_p = 90, 180
    theta = (np.arange(n_t) + 0.5) * (math.pi / 2) / n_t
    phi = (np.arange(n_p) + 0.5) * 2 * math.pi / n_p
    t, p = np.meshgrid(theta, phi, indexing="ij")
    d = np.stack([np.sin(t) * np.sin(p), np.sin(t) * np.cos(p), np.cos(t)], axis=-1)
    L = sky.spectral_radiance(d, [550.0])[..., 0]
    e = float(np.sum(L * np.cos(t) * np.sin(t)) * (math.pi / 2 / n_t) * (2 * math.pi / n_p))
    down = float(sky.diffuse_fluxes([550.0])[0][0])
    assert abs(e / down - 1) < 0.01


@pytest.mark.parametrize("tau, sun", [(20.0, 4.0), (20.0, 30.0), (60.0, 30.0)])
def test_no_peak_about_a_sun_the_cloud_hides(tau, sun):
    """Under a thick cloud nothing of the droplets' forward peak survives (the beam scattered only into the peak is
    exp(-(1 - omega f) tau / mu) < 1e-9 of the sun here), so the radiance about the hidden sun is the overcast's
    smooth field: within 1 deg of the sun no more than 3 % above the field 2 deg away. It was 3.3x (tau 20, sun 4
    deg) and +11 % (tau 20 and 60, sun 30 deg) when the grid's quadrature error was put into the peak's lobe."""
    sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau)
    near = sky.luminance(_dirs([(sun, 0.0), (sun + 0.5, 0.0), (sun + 1.0, 0.0)]))
    ring = sky.luminance(_dirs([(sun + 2.0, 0.0), (sun, 2.0 / math.cos(math.radians(sun)))]))
    assert np.all(near <= 1.03 * ring.max()), (near, ring)


def test_peak_kept_where_the_peak_light_is_real():
    """Under optical depth 5 (sun 30 deg) the peak carries about 4 % of the sun's flux: the aureole stays."""
    sky = CloudySky(math.radians(60.0), 0.0, cloud_optical_depth=5.0)
    lum = sky.luminance(_dirs([(30.0, 0.0), (35.0, 0.0)]))
    assert lum[0] > 4.0 * lum[1]


def test_symmetric_about_the_sun_and_brighter_towards_it():
    sky = CloudySky(math.radians(60.0), math.radians(135.0), cloud_optical_depth=2.0)
    a = math.radians(135.0)
    left = _dirs([(20.0, 135.0 - 70.0)])
    right = _dirs([(20.0, 135.0 + 70.0)])
    np.testing.assert_allclose(sky.luminance(left), sky.luminance(right), rtol=1e-12)
    towards = np.array([[math.cos(0.6) * math.sin(a), math.cos(0.6) * math.cos(a), math.sin(0.6)]])
    away = np.array([[-math.cos(0.6) * math.sin(a), -math.cos(0.6) * math.cos(a), math.sin(0.6)]])
    assert sky.luminance(towards)[0] > 1.5 * sky.luminance(away)[0]


def test_solar_disc_is_attenuated_by_the_cloud():
    clear = _sky(0.0, 60.0)
    cloudy = _sky(2.0, 60.0)
    wl = [555.0]  # a wavelength of the grid: no interpolation
    ratio = cloudy.sun_spectral_radiance(wl)[0] / clear.sun_spectral_radiance(wl)[0]
    # the cloud's optical depth along a slant path of 1 / cos(30 deg) (the shell's curvature: < 1e-4 here)
    tau = float(cloudy.cloud_layer.optical_depth(wl, DATA["cloud_top_m"])[0])
    assert ratio == pytest.approx(math.exp(-tau / math.cos(math.radians(30.0))), rel=1e-4)
    assert _sky(60.0, 30.0).sun_spectral_radiance(wl)[0] < 1e-40


def test_views_from_inside_and_above_the_layer():
    below = _sky(15.0, 40.0)
    above = _sky(15.0, 40.0, altitude=3000.0)
    up, down = np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, -1.0]])
    # above the cloud the sky overhead is clear (dim) and the cloud below bright; below, the reverse
    assert above.luminance(down)[0] > 3 * above.luminance(up)[0]
    assert below.luminance(up)[0] > 3 * below.luminance(down)[0]
    # just below and just above the cloud top (the column lit by the tables, then the whole column in DISORT):
    # the same cloud within 3 % looking down
    d = _dirs([(-45.0, 30.0), (-80.0, 150.0), (45.0, 100.0), (80.0, 10.0)])
    inside = _sky(15.0, 40.0, altitude=1499.0).luminance(d)
    outside = _sky(15.0, 40.0, altitude=1501.0).luminance(d)
    np.testing.assert_allclose(inside[:2], outside[:2], rtol=0.03)
    # looking up from just below the top: the clear sky of the spherical tables (with the cloud's light sent back
    # by the air in the air's own angular shape) against the whole column in DISORT at the same place (its
    # plane-parallel air over the cloud): measured 4.4 / 4.0 % at 45 / 80 deg elevation (in the plane-parallel
    # limit 1.2 / 1.4 %). Until 2026-12-03 this compared 1499 m with 1501 m within 20 % (measured -6 / +15 %),
    # where the metre of cloud above the inside observer brightens the view 30 deg from the sun by itself.
    column = _sky(15.0, 40.0, altitude=1499.0, illumination="column").luminance(d)
    np.testing.assert_allclose(inside[2:], column[2:], rtol=0.05)


def test_xyz_agrees_with_the_spectrum_and_dict_round_trip():
    from skyscatter.spectral import REFERENCE_WAVELENGTHS, spectrum_to_xyz

    sky = _sky(5.0, 25.0)
    d = _dirs([(10.0, 0.0), (45.0, 100.0), (-20.0, 30.0)])
    np.testing.assert_allclose(sky.xyz(d), spectrum_to_xyz(sky.spectral_radiance(d, REFERENCE_WAVELENGTHS),
                                                           REFERENCE_WAVELENGTHS), rtol=1e-10)
    again = registry.from_dict(json.loads(json.dumps(sky.to_dict())))
    np.testing.assert_array_equal(again.xyz(d), sky.xyz(d))


@pytest.mark.parametrize("kw, words", [
    ({"cloud_optical_depth": 61.0}, "cloud_optical_depth"),
    ({"cloud_optical_depth": -1.0}, "cloud_optical_depth"),
    ({"cloud_base": 2000.0, "cloud_top": 1000.0}, "above the cloud base"),
    ({"cloud_effective_radius": 0.5e-6}, "cloud_effective_radius"),
    ({"cloud_top": 25000.0}, "cloud_top"),
    ({"streams": 5}, "streams"),
    ({"altitude": float("nan")}, "altitude"),
])
def test_bad_options_give_one_clear_error(kw, words):
    with pytest.raises(InvalidParameterError, match=words):
        CloudySky(0.5, 0.0, **kw)


def test_twilight_is_lit_by_the_tables_and_darker_than_sunset():
    up = _dirs([(90.0, 0.0), (20.0, 0.0), (20.0, 180.0), (-30.0, 0.0)])
    dusk = _sky(15.0, -3.0).luminance(up)
    sunset = _sky(15.0, 2.0).luminance(up)
    assert np.all(np.isfinite(dusk)) and np.all(dusk > 0)
    assert np.all(dusk < sunset)
    assert _sky(15.0, -3.0).sun.illuminance_normal() == 0.0


def test_photometry_under_the_layer():
    """Horizontal illuminance of the sky (photometry's quadrature of the luminance) against DISORT's diffuse flux
    weighted by the CIE y-bar (683 lm/W); Tregenza patches cover the same light; the sun's illuminance behind
    the cloud is its disc radiance's, attenuated by exp(-tau / mu)."""
    from skyscatter import photometry
    from skyscatter.patches import patch_luminance, patch_scheme
    from skyscatter.spectral import REFERENCE_WAVELENGTHS, spectrum_to_xyz

    sky = _sky(5.0, 35.0)
    e_v = photometry.horizontal_illuminance(sky)
    flux = sky.diffuse_fluxes(REFERENCE_WAVELENGTHS)[0]
    assert e_v == pytest.approx(float(spectrum_to_xyz(flux, REFERENCE_WAVELENGTHS)[1]), rel=0.01)
    scheme = patch_scheme("tregenza")
    lum = patch_luminance(sky, scheme)
    assert lum.shape == (145,) and np.all(lum > 0)
    # the patches' light on a horizontal plane (centre cosines: a coarse quadrature, 3 %)
    assert float(np.sum(lum * scheme.solid_angles * scheme.centre_directions[:, 2])) == pytest.approx(e_v, rel=0.03)
    assert photometry.vertical_illuminance(sky, math.pi) > 0
    clear_sun = _sky(0.0, 35.0).sun.illuminance_normal()
    assert sky.sun.illuminance_normal() < clear_sun * math.exp(-4.0 / math.sin(math.radians(35.0)))


def _nadir_dirs(nadir_deg, azimuth_deg):
    eta, az = np.radians(np.asarray(nadir_deg, float)), math.radians(azimuth_deg)
    return np.stack([np.sin(eta) * math.sin(az), np.sin(eta) * math.cos(az), -np.cos(eta)], axis=-1)


def _plane_parallel(sky, d, wl):
    """The plane-parallel field at the observer (the model before the spherical view): the grid lookup."""
    return sky._spectra(sky._interpolate(sky._field["radiance"], d), np.asarray(wl, float))


def test_spherical_view_from_orbit_shows_the_limb():
    from skyscatter.sky.bruneton import BrunetonSky

    wl = [450.0, 550.0, 650.0]
    sky = CloudySky(math.radians(40.0), math.radians(90.0), cloud_optical_depth=15.0, altitude=400e3)
    r, h, top = sky.atmosphere.bottom_radius, 400e3, 1500.0
    edge = math.degrees(math.asin((r + top) / (r + h)))  # nadir angle of the cloud shell's horizon: 70.23 deg
    clear = BrunetonSky(math.radians(40.0), math.radians(90.0), altitude=h,
                        atmosphere=sky.atmosphere.replace(particles=()))
    for az in (0.0, 90.0, 200.0):
        # beyond the cloud shell's horizon (up to the horizontal and above it): the tables' sky exactly (the limb)
        miss = _nadir_dirs([edge + 0.05, edge + 1.0, 75.0, 89.0, 120.0, 180.0], az)
        np.testing.assert_allclose(sky.spectral_radiance(miss, wl), clear.spectral_radiance(miss, wl), rtol=1e-12,
                                   atol=0.0)
        np.testing.assert_allclose(sky.xyz(miss), clear.xyz(miss), rtol=1e-12, atol=0.0)
        assert sky.luminance(miss[:2]).min() > 0  # the air's glow against black space
        # just inside it: the cloud, not the tables (brighter than the tables' air there: 1.40 times measured at
        # azimuth 0)
        inside = _nadir_dirs([edge - 0.05], az)
        assert sky.luminance(inside)[0] > 1.2 * clear.luminance(inside)[0]
    # the nadir is the plane-parallel column's (the local and the observer's angles coincide there)
    nadir = np.array([[0.0, 0.0, -1.0]])
    np.testing.assert_allclose(sky.spectral_radiance(nadir, wl), _plane_parallel(sky, nadir, wl), rtol=1e-6)


def test_spherical_view_tends_to_the_plane_parallel_one_on_a_huge_planet():
    """On a planet of 1000 Earth radii the sphere's angles and chords are those of the plane-parallel air
    (the local zenith angle at 80 deg nadir from 30 km differs by 2e-5 deg): the spherical view must
    reproduce the old plane-parallel field everywhere the ray meets the cloud."""
    base = AtmosphereParameters()
    rb = base.bottom_radius * 1000.0
    huge = AtmosphereParameters(bottom_radius=rb, top_radius=rb + base.thickness)
    sky = CloudySky(math.radians(50.0), 0.3, cloud_optical_depth=15.0, altitude=30e3, atmosphere=huge)
    wl = [450.0, 550.0, 650.0]
    for az in (0.0, 120.0, 290.0):
        d = _nadir_dirs([0.0, 30.0, 60.0, 80.0, 87.0], az)
        np.testing.assert_allclose(sky.spectral_radiance(d, wl), _plane_parallel(sky, d, wl), rtol=2e-3)


def test_spherical_view_at_aircraft_altitude_changes_little():
    """From 10 km (cloud top 1.5 km) against the plane-parallel field: measured within 0.6 % up to 80 deg from
    the nadir, up to 3 % at 85 deg (sun 40 and 80 deg high; docs/clouds.md); the band within 2.96 deg below the
    horizontal now misses the cloud shell and shows the clear air."""
    sky = CloudySky(math.radians(50.0), 0.0, cloud_optical_depth=15.0, altitude=10e3)
    for az in (0.0, 90.0, 180.0):
        d = _nadir_dirs([0.0, 20.0, 40.0, 60.0, 70.0, 80.0], az)
        new, old = sky.luminance(d), sky._interpolate(sky._xyz_grid, d)[:, 1]
        np.testing.assert_allclose(new, old, rtol=0.01)
        d = _nadir_dirs([85.0], az)
        np.testing.assert_allclose(sky.luminance(d), sky._interpolate(sky._xyz_grid, d)[:, 1], rtol=0.04)


@pytest.mark.parametrize("sun", [2.0, 10.0, 30.0])
def test_no_cloud_is_the_tables_clear_sky_at_a_low_sun(sun):
    """Optical depth 0 is the clear sky: continuous with a layer of optical depth 0.001 (within 3 %; the droplets'
    forward peak of 0.1 % of the beam adds up to 2.4 % at 650 nm, sun 30 deg) and within 3 % of the coupling
    tables' own horizontal sky irradiance on the ground (:meth:`horizontal_sky_irradiance`, the hemisphere
    integral of their sky radiance, [Bruneton2008] Eq. 16; another path through the same tables than the model's
    light on an empty layer carried down through the clear column). Measured 2026-12-05: 0.988-1.000 of optical
    depth 0.001 and -0.3..+1.9 % (sun 2 deg) / +0.6..+2.7 % (10, 30 deg) against the tables. Until then optical
    depth 0 solved the whole clear column in DISORT with a pseudo-spherical beam: at sun 2 deg 0.60-0.67 of the
    sky of optical depth 0.001 (-34..-41 % against the spherical forward photons, docs/clouds.md)."""
    from skyscatter.precomputed.cache import cached_atmosphere
    from skyscatter.sky.cloudy import COUPLING_TABLE_SIZES

    wl = np.array([450.0, 550.0, 650.0])
    z = math.radians(90.0 - sun)
    clear = CloudySky(z, 0.0, cloud_optical_depth=0.0, ground_albedo=0.2)
    thin = CloudySky(z, 0.0, cloud_optical_depth=1e-3, ground_albedo=0.2)
    e0 = clear.diffuse_fluxes(wl)[0]
    assert np.all(np.abs(e0 / thin.diffuse_fluxes(wl)[0] - 1.0) < 0.03)
    tables = cached_atmosphere(clear.atmosphere.replace(particles=()), sizes=COUPLING_TABLE_SIZES, progress=False)
    e_tab = np.interp(wl, tables.wavelengths, tables.horizontal_sky_irradiance([z])[0])
    assert np.all(np.abs(e0 / e_tab - 1.0) < 0.03), e0 / e_tab - 1.0
