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


def test_default_coupling_thin_cloud_sun_10():
    """Optical depth 5, sun 10 deg: measured 3.8 % (450 nm, 2026-12-04; 10 % with the isotropic sky, a strict xfail
    until 2026-12-03)."""
    rel = _relative(5.0, 10.0, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


def test_default_coupling_thin_cloud_low_sun():
    """Optical depth 1, sun 10 deg: measured -4.7 % (450 nm). A strict xfail (-5.4 %) until 2026-12-04, while the
    sky's irradiance on the cloud top was read from the tables' irradiance table (rows 4 km apart in altitude,
    made for the ground) instead of integrated from their sky radiance (docs/clouds.md)."""
    rel = _relative(1.0, 10.0, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


def test_coupling_with_disort_clear_sky_on_the_cloud_top(monkeypatch):
    """The coupling itself, without the tables' error: the cloud top lit by the clear air's own plane-parallel
    DISORT solution (the model's column of the air without the cloud, ``illumination="column"``, at the cloud top:
    its sun's transmittance, diffuse irradiance and radiance) in place of the tables'. Optical depth 1, sun 10 deg
    (the case the tables miss): within 5 % of the reference (measured 3.7 %)."""
    air = _air()
    clear = CloudySky(math.radians(80.0), 0.0, cloud_optical_depth=0.0, ground_albedo=DATA["ground_albedo"],
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
    rel = _relative(1.0, 10.0, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))
