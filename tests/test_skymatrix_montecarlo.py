"""The spectral sky matrix's patches against the Monte Carlo through the same retrieved air and clouds (issue 24,
item 3; the 20-hour comparison with gensdaymtx beside it is benchmarks/compare_spectral_skymatrix_montecarlo.py).

The weather file is made here (tests/weather_synth.py: a SPECTRL2 clear day, a broken and an overcast day); the
tables are the "coarse" preset over the 3 x 2 grid of tests/test_spectral_skymatrix.py (shared builds). Two hours,
one clear and one overcast, 7 patches spread in the sun's frame, 450 and 650 nm (nodes of the coarse tables),
few paths. What the Monte Carlo runs through: tests/skymatrix_mc.py.

Bounds per patch: ``|ours - MC| <= K_SIGMA * SE_MC + allowance * MC`` with K_SIGMA = 4 (a false alarm somewhere
among the 28 comparisons at well under 1 %), and the allowance the model's own error on these tables: clear 6 %
(the coarse preset, 8 x 16 x 32 x 8 scattering tables with 4 orders, is "percent-level less accurate" than the
paper's sizes, whose patches agree with the Monte Carlo to a median |.| of 1.3 % and p95 4.3 %: docs/sky_matrices.md;
the AOD and albedo are interpolated between nodes 0.2 and 0.2 apart), overcast 5 % (the cloud table interpolated
in ln tau and cos z: -0.7 to +0.1 % median, p95 2 % against CloudySky at the exact cloud; CloudySky (DISORT,
16 streams, tables-lit) against the Monte Carlo: docs/clouds.md). Plus the median over the hour's patches within
``MEDIAN_ALLOWANCE`` of the Monte Carlo's (a bias check, tighter than the per-patch bound).
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from skymatrix_mc import away_from_sun, band_e0, matrix_directions, mc_reduced, ours_reduced, parts_of, patch_subset  # noqa: E402
from weather_synth import write_epw  # noqa: E402

pytest.importorskip("xarray")
pytest.importorskip("pvlib")
pytest.importorskip("disortpp")

AOD_NODES = (0.0, 0.2, 0.5)
WAVELENGTHS = (450.0, 650.0)
K_SIGMA = 4.0
ALLOWANCE = {"clear": 0.06, "overcast": 0.05}
MEDIAN_ALLOWANCE = {"clear": 0.03, "overcast": 0.03}
PATHS = {"clear": 2048, "overcast": 2048}


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    from skyscatter.fit.spectral_matrix import band_edges, spectral_sky_matrix
    from skyscatter.fit.weather import CLEAR, CLOUDY, RetrievalOptions, retrieve_hourly_atmosphere

    options = RetrievalOptions(aerosol_optical_depth_nodes=AOD_NODES, tables="coarse")
    epw = write_epw(tmp_path_factory.mktemp("weather") / "synth.epw")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h = retrieve_hourly_atmosphere(epw, options)
        centres = [w + d for w in WAVELENGTHS for d in (-5.0, 0.0, 5.0)]
        ds = spectral_sky_matrix(None, scheme="tregenza", samples=1, bands=centres, atmosphere=h, gases=False)
    zen = np.degrees(h.sun_zenith)
    # the clear day's and the overcast day's hour nearest a sun zenith of 45 deg
    clear = [i for i in range(24) if h.status[i] == CLEAR]
    cloudy = [i for i in range(48, 72) if h.status[i] == CLOUDY]
    hours = {"clear": min(clear, key=lambda i: abs(zen[i] - 45.0)),
             "overcast": min(cloudy, key=lambda i: abs(zen[i] - 45.0))}
    _, edges = band_edges(centres)
    return h, ds, hours, [1, 4], band_e0(edges, [1, 4])


@pytest.mark.parametrize("kind", ["clear", "overcast"])
def test_matrix_patches_against_montecarlo(setup, kind):
    from skyscatter.conventions import direction_from_angles
    h, ds, hours, k_bands, e0 = setup
    i = hours[kind]
    dirs = matrix_directions()
    zen, azi = float(h.sun_zenith[i]), float(h.sun_azimuth[i])
    patches = patch_subset(dirs, azi)[::3]
    sun = direction_from_angles(zen, azi)
    keep = away_from_sun(dirs[patches], sun, kind)
    patches = patches[keep]
    assert patches.size >= 5
    (w, what, air), = parts_of(h, ds, i, kind)
    assert w == 1.0 and what == kind
    mc, se, n, _ = mc_reduced(air, dirs[patches], np.array(WAVELENGTHS), zen, azi, PATHS[kind], seed=24 + i)
    ours = ours_reduced(ds, i, patches, k_bands, e0, float(h.eccentricity[i]))
    rel = ours / mc - 1.0
    bound = K_SIGMA * se / mc + ALLOWANCE[kind]
    report = (f"hour {i} zenith {np.degrees(zen):.1f} deg, {n} paths: rel {np.round(rel * 100, 1).tolist()} %, "
              f"MC SE {np.round(se / mc * 100, 1).tolist()} %")
    print(report)
    assert np.all(np.abs(rel) <= bound), report
    assert abs(np.median(rel)) <= MEDIAN_ALLOWANCE[kind] + K_SIGMA * np.median(se / mc) / np.sqrt(rel.size), report
