"""The DISORT cases of issue 11 against the Monte Carlo reference: precomputed tables vs Monte Carlo, both spherical.

The 12 cases of ``tests/test_precomputed_disort.py`` (aerosol optical depth 0.05, 0.2, 0.5 at 550 nm, Angstrom
exponent 0, no ozone; ground albedo 0.1 and 0.8; sun zenith 30 and 70 deg; principal plane, view zenith 0-70 deg
towards and away from the sun; unit solar irradiance), at 550 nm. DISORT is plane-parallel, so the test against
it carries a sphericity allowance; the Monte Carlo reference (``skyscatter.montecarlo``) traces the same spherical
atmosphere as the tables, so this comparison needs none. Tables: default sizes, the default orders and the
geometric tail (``DEFAULT_ORDERS``; 6 until 2026-12-05, then 8), computed at 550 nm only (cached on disk). Prints a
Markdown table of ``tables / MC - 1`` per direction with the largest Monte Carlo standard error of the row.

    python benchmarks/compare_montecarlo_disort_cases.py [--samples N]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from skyscatter.montecarlo import sky_radiance  # noqa: E402
from skyscatter.precomputed import cached_atmosphere  # noqa: E402
from test_precomputed_disort import VIEW_ZENITH, _params  # noqa: E402

WAVELENGTH = np.array([550.0])


def principal_plane() -> np.ndarray:
    """View directions towards the sun's azimuth (north, +y) and away from it, view zenith 0-70 deg."""
    return np.concatenate([np.stack([0.0 * VIEW_ZENITH, side * np.sin(VIEW_ZENITH), np.cos(VIEW_ZENITH)], axis=-1)
                           for side in (1.0, -1.0)])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=131072, help="Monte Carlo paths per direction")
    args = ap.parse_args()
    dirs = principal_plane()
    n_v = VIEW_ZENITH.size
    t0 = time.perf_counter()
    print("| AOD | albedo | sun zenith | towards the sun, view zenith 0..70 deg [%] | away from the sun [%] | "
          "largest abs. | MC stderr (largest) |")
    print("|---|---|---|---|---|---|---|")
    worst = 0.0
    for aod in (0.05, 0.2, 0.5):
        for albedo in (0.1, 0.8):
            params = _params(aod, albedo)
            tables = cached_atmosphere(params, wavelengths=WAVELENGTH, progress=False)
            pos = np.array([0.0, 0.0, params.bottom_radius])
            for sz in (30.0, 70.0):
                zen = math.radians(sz)
                sun = np.array([0.0, math.sin(zen), math.cos(zen)])
                tab = np.asarray(tables.sky_radiance(pos, dirs, sun))[:, 0]
                mc = sky_radiance(params, dirs, WAVELENGTH, sun_zenith=zen, samples=args.samples, seed=7)
                rel = 100.0 * (tab / mc.radiance[:, 0] - 1.0)
                rse = 100.0 * mc.stderr[:, 0] / mc.radiance[:, 0]
                worst = max(worst, float(np.max(np.abs(rel))))
                towards = " ".join(f"{v:+.1f}" for v in rel[:n_v])
                away = " ".join(f"{v:+.1f}" for v in rel[n_v:])
                print(f"| {aod:g} | {albedo:g} | {sz:.0f} | {towards} | {away} | {np.max(np.abs(rel)):.1f} | "
                      f"{np.max(rse):.2f} |", flush=True)
    print(f"\nlargest |tables / MC - 1|: {worst:.1f} %; {args.samples} paths per direction; "
          f"{time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
