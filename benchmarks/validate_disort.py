"""Precomputed tables vs DISORT with aerosols: the table of docs/bruneton.md (issue 11).

Same cases and settings as tests/test_precomputed_disort.py (aerosol optical depth 0.05, 0.2, 0.5 at 550 nm,
ground albedo 0.1 and 0.8, sun zenith 30 and 70 deg, principal plane, view zenith 0-70 deg), printing the
relative error of every direction; ``--default-sizes`` uses the default table sizes.

    PYTHONPATH=src python benchmarks/validate_disort.py [--default-sizes]
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from disort_reference import disort_radiance  # noqa: E402
from skyscatter.precomputed import PrecomputedAtmosphere  # noqa: E402
from test_precomputed_disort import SIDES, SIZES, VIEW_ZENITH, _params, sphericity_allowance  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--default-sizes", action="store_true")
    args = ap.parse_args()
    sizes = None if args.default_sizes else SIZES
    print("| AOD | albedo | sun zenith | side | error at view zenith 0, 10, ..., 70 deg [%] | max | allowed at 70 |")
    print("|---|---|---|---|---|---|---|")
    for aod in (0.05, 0.2, 0.5):
        for albedo in (0.1, 0.8):
            p = _params(aod, albedo)
            atm = PrecomputedAtmosphere.compute(p, orders=6, wavelengths=[550.0], sizes=sizes, progress=False)
            for sz in (30.0, 70.0):
                ts = math.radians(sz)
                ref = disort_radiance(p, 550.0, ts, VIEW_ZENITH, SIDES, n_layers=100, n_streams=32, n_moments=200)
                tol = 0.03 + sphericity_allowance(p, ts, VIEW_ZENITH)
                for j, (side, name) in enumerate(((1.0, "towards sun"), (-1.0, "away"))):
                    d = np.stack([side * np.sin(VIEW_ZENITH), 0 * VIEW_ZENITH, np.cos(VIEW_ZENITH)], axis=-1)
                    ours = atm.sky_radiance([0.0, 0.0, p.bottom_radius], d, [math.sin(ts), 0.0, math.cos(ts)])[:, 0]
                    err = 100 * (ours / ref[:, j] - 1)
                    print(f"| {aod} | {albedo} | {sz:.0f} | {name} | {' '.join(f'{e:+.1f}' for e in err)} | "
                          f"{np.abs(err).max():.1f} | {100 * tol[-1]:.1f} |", flush=True)


if __name__ == "__main__":
    main()
