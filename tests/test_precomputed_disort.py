"""Multiple scattering with aerosols against DISORT (issue 11, item 0).

The precomputed tables (Bruneton & Neyret 2008, doi:10.1111/j.1467-8659.2008.01245.x) against the
plane-parallel discrete-ordinates solver DISORT (Stamnes et al. 1988, doi:10.1364/AO.27.002502; disortpp) for
aerosol optical depths 0.05, 0.2 and 0.5 at 550 nm (single-scattering albedo 0.9, Cornette-Shanks g = 0.8,
scale height 1.2 km), ground albedo 0.1 and 0.8, sun zenith 30 and 70 deg: radiance at the ground along the
solar principal plane, view zenith 0-70 deg on both sides of the zenith.

Tolerance: 3 % plus a sphericity allowance. DISORT is plane-parallel, the tables are spherical. To first order in
H / R, the slant optical depth of an exponential layer of scale height H at zenith angle theta is
``tau sec(theta) (1 - (H / R) tan^2 theta)`` (expand ``h(s) = s cos(theta) + s^2 sin^2(theta) / (2 R)`` in
``integral exp(-h / H) ds``). The sun's beam and the view path are attenuated by that much less, and the number of
scatterers along the view path is smaller by the same relative amount, so the relative difference is bounded by
``(H_R / R) tan^2 theta_v + sum_i tau_i (H_i / R) (sec(theta_s) tan^2 theta_s + sec(theta_v) tan^2 theta_v)``
(0.95 % + 0.5 % at 70 deg, under 0.1 % at 30 deg).

Optical depth 0.5 over albedo 0.8 was 3-10 % low away from the sun until the orders beyond the sixth were added as
their geometric tail (they carry ~13 % of the radiance there) and the scattering density was interpolated per unit
scattering coefficient (interpolating J itself between radii overestimated it: +5 to +7 % once converged).

Before the fix (issue 11) the tables were +17.6 % at the zenith and +44 % 20 deg from it away from the sun for
optical depth 0.2 and the sun at 30 deg: the ``mu`` and ``mu_s`` table axes each left 36-42 deg around the zenith
in a single cell, and the clamped ``nu`` texels held values at other view-sun angles than their coordinates,
across which the forward-peaked multiple scattering of the aerosols was interpolated.
"""

import math

import numpy as np
import pytest

from disort_reference import TABLE_SIZES as SIZES
from disort_reference import disort_radiance, sphericity_allowance
from skyscatter.precomputed import AtmosphereParameters, cached_atmosphere

disortpp = pytest.importorskip("disortpp")

VIEW_ZENITH = np.radians(np.arange(0.0, 71.0, 10.0))
SIDES = np.radians([0.0, 180.0])  # towards the sun's azimuth, away from it


def _params(aod: float, albedo: float) -> AtmosphereParameters:
    return AtmosphereParameters(mie_angstrom_alpha=0.0, mie_angstrom_beta=aod, ozone_column=0.0,
                                ground_albedo=albedo, solar_irradiance=1.0)


@pytest.fixture(scope="session")
def disort_tables():
    """Tables for every (optical depth, albedo) pair, computed once per session (550 nm only): through the
    session's table cache, so that parallel workers running tests of this module share one build."""
    out = {}
    for aod in (0.05, 0.2, 0.5):
        for albedo in (0.1, 0.8):
            out[aod, albedo] = cached_atmosphere(_params(aod, albedo), orders=6, wavelengths=[550.0], sizes=SIZES,
                                                 progress=False)
    return out


@pytest.mark.slow
@pytest.mark.parametrize("aod", [0.05, 0.2, pytest.param(0.5, id="0.5")])
@pytest.mark.parametrize("albedo", [0.1, 0.8])
@pytest.mark.parametrize("sun_zenith_deg", [30.0, 70.0])
def test_aerosol_multiple_scattering_against_disort(disort_tables, aod, albedo, sun_zenith_deg):
    atm = disort_tables[aod, albedo]
    p = atm.parameters
    theta_s = math.radians(sun_zenith_deg)
    ref = disort_radiance(p, 550.0, theta_s, VIEW_ZENITH, SIDES, n_layers=100, n_streams=32, n_moments=200)
    sun = np.array([math.sin(theta_s), 0.0, math.cos(theta_s)])
    tol = 0.03 + sphericity_allowance(p, theta_s, VIEW_ZENITH)
    for j, side in enumerate((1.0, -1.0)):
        d = np.stack([side * np.sin(VIEW_ZENITH), np.zeros_like(VIEW_ZENITH), np.cos(VIEW_ZENITH)], axis=-1)
        ours = atm.sky_radiance([0.0, 0.0, p.bottom_radius], d, sun)[:, 0]
        err = ours / ref[:, j] - 1.0
        assert np.all(np.abs(err) < tol), (side, np.round(100 * err, 2), np.round(100 * tol, 2))


def test_hardest_case_against_the_monte_carlo_reference(disort_tables):
    """Issue 11, item 0, against the Monte Carlo reference: the same spherical atmosphere on both sides, so no
    sphericity allowance. The hardest DISORT case (aerosol optical depth 0.5 over albedo 0.8, sun zenith 70 deg,
    where orders 7 and up carry ~13 % of the radiance), principal plane, view zenith 0-70 deg, 550 nm.

    Each direction within the issue's 3 % plus 3 Monte Carlo standard errors (1.0-1.9 % with 32768 paths); the
    mean over the 16 directions, whose standard error is 0.34 %, within 3 % including 3 of its standard errors.
    Seeded, so deterministic. (All 12 cases at the default table sizes with 131072 paths:
    ``benchmarks/compare_montecarlo_disort_cases.py``, within 2.8 %, docs/accuracy.md.)"""
    from skyscatter.montecarlo import sky_radiance

    params = _params(0.5, 0.8)
    zen = math.radians(70.0)
    sun = np.array([0.0, math.sin(zen), math.cos(zen)])
    dirs = np.concatenate([np.stack([0.0 * VIEW_ZENITH, side * np.sin(VIEW_ZENITH), np.cos(VIEW_ZENITH)], axis=-1)
                           for side in (1.0, -1.0)])
    tab = disort_tables[0.5, 0.8].sky_radiance(np.array([0.0, 0.0, params.bottom_radius]), dirs, sun)[:, 0]
    mc = sky_radiance(params, dirs, np.array([550.0]), sun_zenith=zen, samples=32768, seed=3)
    rel = tab / mc.radiance[:, 0] - 1.0
    rse = mc.stderr[:, 0] / mc.radiance[:, 0]
    assert np.all(np.abs(rel) < 0.03 + 3.0 * rse), rel
    mean_se = math.sqrt(float(np.sum(rse**2))) / rel.size
    assert abs(rel.mean()) + 3.0 * mean_se < 0.03, (rel.mean(), mean_se)
