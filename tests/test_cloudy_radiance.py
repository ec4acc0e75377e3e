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
coupling with the precomputed clear sky (``illumination="tables"``) in the same limit: within 5 % under optical
depths 15-60 with the sun 30-60 deg high (measured up to 1.0 %); with the sun 10 deg high it misses (optical
depths 15-60: -5.6 to -6.1 % at 450 nm; 1 and 5: 27 and 10 %), strict xfails.
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
@pytest.mark.parametrize("sun", [60.0, 30.0])
def test_default_coupling_within_5_percent_of_disort(tau, sun):
    """The default illumination (the column from the cloud top down, lit by the precomputed clear sky): measured up
    to 1.0 %."""
    rel = _relative(tau, sun, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


@pytest.mark.xfail(strict=True, reason="sun 10 deg: -5.6 to -6.1 % at 450 nm (every view low, worst 45 deg high "
                                       "towards the sun; 550 nm -2.1 to -2.6 %); passed (-3.6 to -4.7 %) only while "
                                       "the droplets' aliased phase function biased the comparison (docs/clouds.md)")
@pytest.mark.parametrize("tau", [15.0, 30.0, 60.0])
def test_default_coupling_thick_cloud_sun_10(tau):
    rel = _relative(tau, 10.0, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))


@pytest.mark.xfail(strict=True, reason="thin clouds at a low sun: the sky's light on the cloud top enters as an "
                                       "isotropic radiance, flux-corrected only (docs/clouds.md): 10-27 %")
@pytest.mark.parametrize("tau", [1.0, 5.0])
def test_default_coupling_thin_cloud_low_sun(tau):
    rel = _relative(tau, 10.0, "tables")
    assert np.max(np.abs(rel)) < 0.05, np.max(np.abs(rel))
