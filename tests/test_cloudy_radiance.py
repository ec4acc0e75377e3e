"""The cloudy sky's radiance under uniform cloud layers against plane-parallel DISORT (issue 22 item 5: radiance
10 deg or more above the horizon within 5 %; docs/clouds.md, "Radiance under clouds").

Reference (not the model's code): tests/data/cloudy_radiance_disort.json, written by
benchmarks/cloudy_radiance_disort.py (deterministic): ``disort_reference.disort_cloud`` (disortpp, its own 100
layers, 400 Legendre moments of the droplets' Mie table, delta-M plus the Nakajima-Tanaka TMS correction added
explicitly) at 64 streams, Rayleigh air + the water cloud 1000-1500 m (r_e 10 um), ground albedo 0.2, 450 / 550 /
650 nm, 23 views 10-90 deg high at azimuths 0-180 deg from the sun, optical depths 1, 5, 15, 30, 60 and suns 60,
30, 10, 2 deg high. Views within 25 deg of the sun are not compared (the aureole inside the diffraction peak).
That DISORT setup agrees with the Monte Carlo within 2 % + 3 standard errors on 192 views (docs/clouds.md).

The model is evaluated in the same plane-parallel setup (a planet of 1000 Earth radii) with the whole column in
DISORT (``illumination="column"``): within 5 % for optical depths 1-60 at every sun (measured up to 0.8 %, since
the droplets' Mie optics resolve the size integral: until 2026-12-03 their 24 nodes per e aliased the phase
function's ripple with size into a ripple with wavelength, up to 7 % at 650 nm under optical depth 1). The default
coupling with the precomputed clear sky (``illumination="tables"``, the sky's light on the cloud top with its
angular distribution) in the same limit: within 5 % under optical depths 1-60 with the sun 30-60 deg high
(measured up to 1.8 %) and 5-60 with it 10 deg high (up to 4.4 %); optical depth 1 at 10 deg misses (-5.4 %
at 450 nm: the coupling tables' clear sky on this planet), a strict xfail.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.sky.cloudy import CloudySky

pytest.importorskip("disortpp")

DATA = json.loads((Path(__file__).parent / "data" / "cloudy_radiance_disort.json").read_text())
WL = DATA["wavelengths_nm"]
CASES = {(c["tau"], c["sun_elevation_deg"]): c for c in DATA["cases"]}


def _air() -> AtmosphereParameters:
    """The reference's air without the cloud on a planet of 1000 Earth radii (the plane-parallel limit)."""
    rb = AtmosphereParameters().bottom_radius * 1000.0
    return AtmosphereParameters(bottom_radius=rb, top_radius=rb + 60000.0, mie_angstrom_beta=0.0, ozone_column=0.0,
                                ground_albedo=DATA["ground_albedo"])


def _directions() -> np.ndarray:
    v = np.radians(np.array(DATA["views_deg"]))
    return np.stack([np.cos(v[:, 0]) * np.sin(v[:, 1]), np.cos(v[:, 0]) * np.cos(v[:, 1]), np.sin(v[:, 0])], axis=-1)


def _relative(tau: float, sun: float, illumination: str = "column") -> np.ndarray:
    """Model / DISORT - 1 at the views 25 deg or more from the sun, (n_far, 3)."""
    case = CASES[(tau, sun)]
    air = _air()
    sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=DATA["cloud_base_m"],
                    cloud_top=DATA["cloud_top_m"], ground_albedo=DATA["ground_albedo"], atmosphere=air,
                    illumination=illumination)
    model = sky.spectral_radiance(_directions(), WL) / air.solar_irradiance_at(WL)[None, :]
    far = ~np.array(case["near_sun"])
    return (model / np.array(case["disort64"]) - 1.0)[far]


def test_reference_is_converged_in_streams():
    """The reference at 32 and at 64 streams: within 1.5 % 25 deg or more from the sun (measured: 0.8 %, under
    optical depth 1 and a sun 60 deg high; 0.01 % from optical depth 15 on). Without the TMS correction they
    differed by up to 6 % under optical depth 1, which is why it is added."""
    assert len(CASES) == 20
    for case in DATA["cases"]:
        far = ~np.array(case["near_sun"])
        rel = np.array(case["disort32"])[far] / np.array(case["disort64"])[far] - 1.0
        assert np.max(np.abs(rel)) < 0.015, (case["tau"], case["sun_elevation_deg"], np.max(np.abs(rel)))


@pytest.mark.parametrize("tau", [5.0, 15.0, 30.0, 60.0])
@pytest.mark.parametrize("sun", [60.0, 30.0, 10.0, 2.0])
def test_radiance_within_5_percent_of_disort(tau, sun):
    """Optical depths 5-60: within the 5 % target at every view 10 deg or more above the horizon."""
    rel = _relative(tau, sun)
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


@pytest.mark.parametrize("sun", [60.0, 10.0])
def test_thin_cloud_radiance_within_5_percent_of_disort(sun):
    """Optical depth 1 (mostly single scattering, so it follows the droplets' phase function): measured 0.8 % (sun
    60 deg) and 0.5 % (sun 10 deg); 6.7 and 6.5 % while the droplets' size quadrature aliased the phase function."""
    rel = _relative(1.0, sun)
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


@pytest.mark.parametrize("tau", [15.0, 30.0, 60.0])
@pytest.mark.parametrize("sun", [60.0, 30.0, 10.0])
def test_default_coupling_within_5_percent_of_disort(tau, sun):
    """The default illumination (the column from the cloud top down, lit by the precomputed clear sky with its
    angular distribution): measured up to 0.7 % (sun 30-60 deg) and 3.1 % (sun 10 deg, 450 nm; 2026-12-04). Sun
    10 deg was a strict xfail (-5.6 to -6.1 %) while the sky's light entered as isotropic radiance with corrected
    fluxes and the air's return of the cloud's light was taken as Lambertian."""
    rel = _relative(tau, sun, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


@pytest.mark.parametrize("tau", [1.0, 5.0])
@pytest.mark.parametrize("sun", [60.0, 30.0])
def test_default_coupling_thin_cloud_within_5_percent_of_disort(tau, sun):
    """Thin clouds, the default coupling: measured up to 2.7 % (optical depth 1, sun 30 and 60 deg; 2026-12-04);
    8-14 % before the sky's angular distribution lit the column."""
    rel = _relative(tau, sun, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


@pytest.mark.xfail(strict=True, reason="the coupling tables' clear sky on a planet of 1000 Earth radii, -5.6 % "
                   "at 450 nm on the cloud top (-5.7 %; docs/clouds.md)")
def test_default_coupling_thin_cloud_sun_10():
    """Optical depth 5, sun 10 deg: measured -5.7 % (450 nm, 2026-12-04), a strict xfail. It was -3.8 % (a real test)
    while the adding method took only the ground's albedo out of the tables' sky on the cloud top, +1.5 % too much
    light at 450 nm that hid part of the tables' -5.6 % on this planet of 1000 Earth radii (docs/clouds.md); the
    coupling itself is within 0.5 % here (:func:`test_coupling_with_disort_clear_sky_on_the_cloud_top`), the
    tables' sky at the Earth's radius within 0.9 % of the Monte Carlo
    (``tests/test_cloudy_sky.py::test_tables_sky_on_the_cloud_top_against_backward_paths``)."""
    rel = _relative(5.0, 10.0, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


@pytest.mark.xfail(strict=True, reason="the coupling tables' clear sky on a planet of 1000 Earth radii, -5.6 % "
                   "at 450 nm on the cloud top (-6.9 %; docs/clouds.md)")
def test_default_coupling_thin_cloud_low_sun():
    """Optical depth 1, sun 10 deg: measured -6.9 % (450 nm, 2026-12-04), a strict xfail again. A strict xfail
    (-5.4 %) until the sky's irradiance on the cloud top came from the tables' radiance (2026-12-04), then a real
    test (-4.7 %) while the adding method took only the ground's albedo out of the tables' sky (+1.5 % too much
    light at 450 nm, which hid part of the tables' -5.6 % on this planet); the coupling itself is within 1.9 %
    (:func:`test_coupling_with_disort_clear_sky_on_the_cloud_top`)."""
    rel = _relative(1.0, 10.0, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


def _disort_sky_on_the_cloud_top(monkeypatch, sun: float) -> None:
    """Light the cloud top with the clear air's own plane-parallel DISORT solution (the model's column of the air
    without the cloud, ``illumination="column"``, at the cloud top: its sun's transmittance, diffuse irradiance and
    radiance) in place of the tables' clear sky (the coupling without the tables' error on this planet)."""
    air = _air()
    clear = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=0.0, ground_albedo=DATA["ground_albedo"],
                      atmosphere=air, altitude=DATA["cloud_top_m"], illumination="column")

    def sky(self, wl, height, theta, phi):
        t, p = np.meshgrid(theta, phi, indexing="ij")
        d = np.stack([np.sin(t) * np.sin(p), np.sin(t) * np.cos(p), np.cos(t)], axis=-1)
        return clear.spectral_radiance(d, wl) / air.solar_irradiance_at(wl)

    def light(self, wl, height):
        return (clear._direct.copy(),
                clear.diffuse_fluxes(wl)[0] / (math.pi * air.solar_irradiance_at(wl)))

    monkeypatch.setattr(CloudySky, "_table_sky", sky)
    monkeypatch.setattr(CloudySky, "_table_illumination", light)


@pytest.mark.parametrize("sun", [10.0, 2.0])
@pytest.mark.parametrize("tau", [1.0, 5.0, 15.0, 30.0, 60.0])
def test_coupling_with_disort_clear_sky_on_the_cloud_top(monkeypatch, tau, sun):
    """The coupling itself, without the tables' error on this planet (:func:`_disort_sky_on_the_cloud_top`), at the
    low suns where the tables miss: within 5 % at every optical depth. Measured (2026-12-04, since the light that the
    clear air below the cloud top sends up is taken out of the tables' sky by the same adding as the cloud's,
    ``CloudySky._clear_below``): sun 10 deg +1.9 % (optical depth 1), +0.4..+0.5 % (5-60); sun 2 deg -1.0 % (1),
    -0.5 % (5-60). Before (the ground's albedo alone taken out): sun 10 deg +3.7 % (1), +1.5..+2.0 % (5-60); sun 2
    deg +1.8 % (1), +0.8..+0.9 % (5-60). The default coupling's misses there (:func:`test_default_coupling_sun_2`,
    :func:`test_default_coupling_thin_cloud_low_sun`) are the tables' clear sky on this planet of 1000 Earth radii
    (its diffuse irradiance on the cloud top against the clear column's DISORT: sun 10 deg -5.6 / -2.2 / +0.1 %,
    sun 2 deg +6.5 / +11.2 / +5.7 % at 450 / 550 / 650 nm), not the coupling."""
    _disort_sky_on_the_cloud_top(monkeypatch, sun)
    rel = _relative(tau, sun, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


@pytest.mark.xfail(strict=True, reason="the coupling tables' clear sky on a planet of 1000 Earth radii "
                   "(+5.8 %, 450 nm; docs/clouds.md)")
def test_default_coupling_sun_2():
    """Sun 2 deg, the default coupling in the plane-parallel limit, optical depth 1: measured +5.8 % at 450 nm
    (2026-12-04; 5-60: +5.0 %, on the line, not tested; both +6.0..+6.6 % before the light the clear air below the
    top sends up was taken out by the adding method). The coupling itself is within 1.0 % there
    (:func:`test_coupling_with_disort_clear_sky_on_the_cloud_top`); at the Earth's radius the tables' clear sky on
    the cloud top is within 0.6 / 1.8 / 0.5 % of backward Monte Carlo paths
    (``tests/test_cloudy_sky.py::test_tables_sky_on_the_cloud_top_against_backward_paths``)."""
    rel = _relative(1.0, 2.0, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))
