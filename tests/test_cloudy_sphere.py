"""The cloudy sky at a low sun against forward photons through the true spherical atmosphere (docs/clouds.md,
"Forward photons in the sphere").

Reference (not the model's code): tests/data/cloudy_sphere_forward.json, written by
benchmarks/cloudy_sphere_reference.py with :func:`skyscatter.montecarlo.sphere.sphere_ground_fluxes` (seeds and
photon counts recorded per run): the water cloud 1000-1500 m (r_e 10 um), Earth air, ground albedo 0.2, the Earth's
radius, 450 / 550 / 650 nm, the diffuse irradiance of the ring of local sun elevation 0.5 deg wide centred on the
sun's elevation, pooled over the stored seeds (``tests/cloudy_cct_reference.py``).

* The photons against the independent estimators where those are trustworthy (3 combined standard errors): the
  pooled backward paths at sun 2 deg under optical depths 1, 5 and 15 (``reference``: 0.4-1.6 million paths, their
  error the larger of the pooled one and the runs' scatter); at sun 10 deg the pooled forward photons of the
  periodic domain (``cloudy_low_sun.json``, ``cloudy_montecarlo.json``) plus their domain's error in a sphere, at
  most 1.6 % under these layers (docs/clouds.md, "What the references are worth") - a stated margin, since their
  sky light on the cloud top is short there (about -1.8 % at 450 nm at the ground).
* The model (default coupling) against the photons: the issue's targets, diffuse irradiance within 3 %, CCT
  within 200 K and the radiance 10 deg or more above the horizon within 5 % (the bins' mean difference per
  wavelength), held for the rows that meet them (the misses are in docs/clouds.md with their size).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from cloudy_cct_reference import (
    FINE,
    MONTECARLO,
    WAVELENGTHS,
    model_bin_mean,
    monte_carlo_cct,
    reference,
    sphere_radiance_bins,
    sphere_reference,
)
from skyscatter.sky.cloudy import CloudySky

pytest.importorskip("disortpp")

#: the periodic domain's error in a sphere at sun 10 deg under these layers (docs/clouds.md)
DOMAIN_MARGIN = 0.016
#: the issue's targets
DIFFUSE_TARGET = 0.03
CCT_TARGET_K = 200.0


def _model(tau: float, sun: float) -> tuple[np.ndarray, np.ndarray]:
    sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=MONTECARLO["cloud_base_m"],
                    cloud_top=MONTECARLO["cloud_top_m"], ground_albedo=MONTECARLO["ground_albedo"])
    return sky.diffuse_fluxes(FINE)[0], sky.diffuse_fluxes(WAVELENGTHS)[0]


@pytest.mark.parametrize("tau", [1.0, 5.0, 15.0])
def test_sphere_photons_against_pooled_backward_paths_at_sun_2_deg(tau):
    mc, mce, _ = sphere_reference(tau, 2.0)
    assert np.all(mce < 0.01 * mc)
    bwd = reference(tau, 2.0)
    assert bwd is not None and bwd[3] == "backward"
    np.testing.assert_array_less(np.abs(mc - bwd[0]), 3.0 * np.hypot(mce, bwd[1]))


@pytest.mark.parametrize("tau, sun", [(1.0, 10.0), (5.0, 10.0), (15.0, 10.0), (30.0, 10.0), (5.0, 30.0),
                                      (30.0, 30.0)])
def test_sphere_photons_against_periodic_domain_photons(tau, sun):
    """Sun 10 and 30 deg: the periodic domain's error in a sphere (at most 1.6 % at 10 deg, less higher up) is the
    stated margin (measured -0.3..+3.1 %, at most 3.1 combined sigma; the sphere's photons higher at 450 nm,
    +1.0..+2.4 %, as that domain's deficit of sky light on the cloud top says)."""
    mc, mce, _ = sphere_reference(tau, sun)
    dom = reference(tau, sun)
    assert dom is not None and dom[3] == "forward"
    np.testing.assert_array_less(np.abs(mc - dom[0]), 3.0 * np.hypot(mce, dom[1]) + DOMAIN_MARGIN * mc)


#: (optical depth, sun elevation) rows where the model meets the diffuse target: all measured (docs/clouds.md,
#: 2026-12-05, with the spectral reads as ratios to the ozone transmittance, ``sky.cloudy.ozone_read``): sun 2 deg
#: 450 / 550 / 650 nm -1.6 / -1.6 / -0.2 % (optical depth 1), -1.4 / -1.5 / +0.7 (5), -0.6 / -1.2 / -0.3 (15;
#: -2.1 / -1.6 / +0.4 against the first 5-7 million photons),
#: -1.3 / -2.4 / -0.8 (30), -0.7 / -2.3 / -0.5 (60); sun 10 deg +0.1 / -1.0 / +0.2 (1), +0.2 / -1.6 / +1.0 (15).
#: Before the ozone reads 550 nm missed under 1 / 30 / 60 at sun 2 deg (-3.1 / -3.8 / -3.7 %).
#: Sun 10 and 30 deg under 5 and 30 (seeds 901 and 902, 2026-12-05): -0.7 / -0.5 / +0.3 (5, 10 deg), -0.8 / +0.1 /
#: +0.0 (30, 10 deg), -0.8 / +0.1 / +0.8 (5, 30 deg), -0.8 / +0.1 / +0.1 (30, 30 deg).
DIFFUSE_ROWS = [(1.0, 2.0), (5.0, 2.0), (15.0, 2.0), (30.0, 2.0), (60.0, 2.0), (1.0, 10.0), (5.0, 10.0), (15.0, 10.0),
                (30.0, 10.0), (5.0, 30.0), (30.0, 30.0)]
#: rows where it meets the CCT target, measured the same day: -118..+103 K; optical depth 15 at sun 2 deg was -201 K
#: (sigma 103 K) against 5-7 million photons per wavelength, a strict xfail until two more seeds (501, 601, 10
#: million photons each per wavelength) put it at +15 +- 45 K (the model -0.6 / -1.2 / -0.3 %; the first seeds'
#: 450 nm values were 1.5-2.1 % above the new ones); sun 10 deg under 5 / 30 -36 / -52 K, sun 30 deg -54 / -39 K
CCT_ROWS = DIFFUSE_ROWS


@pytest.mark.parametrize("tau, sun", DIFFUSE_ROWS)
def test_cloudy_diffuse_irradiance_against_sphere_photons(tau, sun):
    mc, _, _ = sphere_reference(tau, sun)
    _, model = _model(tau, sun)
    np.testing.assert_array_less(np.abs(model / mc - 1.0), DIFFUSE_TARGET)


@pytest.mark.parametrize("tau, sun", CCT_ROWS)
def test_cloudy_cct_against_sphere_photons(tau, sun):
    mc, mce, _ = sphere_reference(tau, sun)
    spectrum, model = _model(tau, sun)
    t_model, t_mc, sigma = monte_carlo_cct(spectrum, model, mc, mce)
    assert abs(t_model - t_mc) <= CCT_TARGET_K, (t_model, t_mc, sigma)


#: the issue's radiance target (10 deg or more above the horizon)
RADIANCE_TARGET = 0.05
#: (optical depth, sun elevation) rows where the model's radiance meets it (docs/clouds.md, 2026-12-05, bin means
#: per wavelength 450 / 550 / 650 nm): sun 2 deg -0.9 / -0.5 / +2.1 % (optical depth 1), -2.1 / -0.2 / +1.2 (5),
#: -0.8 / -1.5 / +0.4 (15), +0.6 / -2.5 / -0.7 (30), -0.4 / -3.0 / -0.5 (60); sun 10 deg -1.5 / -2.6 / -0.9 (1),
#: +0.1 / -1.8 / +1.2 (15), -0.0 / +0.1 / +0.4 (5), -0.4 / +0.2 / -0.4 (30); sun 30 deg -1.2 / -0.9 / +0.2 (5), -0.9 /
#: +0.0 / +0.6 (30)
RADIANCE_ROWS = DIFFUSE_ROWS


@pytest.mark.parametrize("tau, sun", RADIANCE_ROWS)
def test_cloudy_radiance_against_sphere_photons(tau, sun):
    """The model's radiance averaged over each stored bin 10 deg or more above the horizon against the photons'
    bin means (run sets of the same bins pooled): the mean over the bins of the relative difference, per
    wavelength, within 5 % (single bins carry 1.5-9 % of the photons' noise; the figures per bin are in
    docs/clouds.md)."""
    bins = sphere_radiance_bins(tau, sun)
    assert len(bins) >= 6
    sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=MONTECARLO["cloud_base_m"],
                    cloud_top=MONTECARLO["cloud_top_m"], ground_albedo=MONTECARLO["ground_albedo"])
    diff = np.array([model_bin_mean(sky, z, a, WAVELENGTHS) / mc - 1.0 for z, a, mc, _, _ in bins])
    np.testing.assert_array_less(np.abs(diff.mean(axis=0)), RADIANCE_TARGET)
