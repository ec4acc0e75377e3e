"""Which interpolation of the tables makes maritime-clean (optical depth 0.5, sun at 70 deg) low against DISORT at
the DISORT tests' 16 radius rows (docs/aerosols.md, "Tables vs DISORT"): the orders' scattering density read
between radius rows along the view rays (:func:`skyscatter.precomputed.kernels.multiple_scattering_kernel`).

Tables of 31 rows (uniform in rho, as every table: the 16 rows of the tests are its even rows) are computed with
the scattering density of each order 2+ replaced, in the rows named by ``--replace`` (odd rows of the 31), by
what the 16-row tables would read there: the two even rows' values at the same texel combined as
:func:`skyscatter.precomputed.sampling.r_mu_cell` weighs them (the weight in rho, 1/2, except in the 16 rows' cell
touching the ground, 0-268 m, read with the altitude weight, 1/4 at row 1 (67 m); the per-row mu coordinate of that
cell is not emulated). Everything else (the rows' own densities, single scattering, irradiance) is the 31 rows'.
``--interp quadratic`` puts instead the quadratic through three even rows (in rho; a candidate repair). Prints
tables / DISORT - 1 [%] in the principal plane as benchmarks/maritime_disort_sizes.py.

    PYTHONPATH=src python benchmarks/maritime_density_rows.py --replace none all ground second above
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from disort_reference import TABLE_SIZES, disort_radiance  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.precomputed import PrecomputedAtmosphere  # noqa: E402
from skyscatter.precomputed import compute as compute_module  # noqa: E402
from test_precomputed_disort import SIDES, VIEW_ZENITH  # noqa: E402

#: odd rows of the 31 replaced, per name: the 16 rows' ground cell (0-268 m), its second cell (268-1070 m), above
ROWS = {"none": [], "all": list(range(1, 30, 2)), "ground": [1], "second": [3], "above": list(range(5, 30, 2))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--replace", nargs="+", default=["none", "all"], choices=sorted(ROWS))
    ap.add_argument("--interp", default="table", choices=("table", "quadratic"))
    ap.add_argument("--sun-zenith", type=float, default=70.0, help="[deg]")
    args = ap.parse_args()
    p = AtmosphereParameters.with_aerosol_type("maritime-clean", 0.5, 50.0, ozone_column=0.0, ground_albedo=0.1,
                                               solar_irradiance=1.0)
    ts = math.radians(args.sun_zenith)
    sun = [math.sin(ts), 0.0, math.cos(ts)]
    ref = disort_radiance(p, 550.0, ts, VIEW_ZENITH, SIDES, n_layers=100, n_streams=32, n_moments=400)
    original = compute_module.multiple_scattering
    for name in args.replace:
        rows = ROWS[name]

        def patched(medium, sizes, transmittance, density, block, rows=rows):
            if block.start == 0 and rows:  # once per order: every block reads the same loaded table
                even = density[0::2].copy()
                for i in rows:
                    k = i // 2  # the 16 rows' cell (k, k + 1)
                    if args.interp == "quadratic":
                        # through the 16 rows k-1, k, k+1 (k, k+1, k+2 at the ground), at rho = k + 1/2
                        a = max(k - 1, 0) if k + 1 < even.shape[0] - 1 else k - 1
                        x = (i / 2.0) - a
                        y0, y1, y2 = even[a], even[a + 1], even[a + 2]
                        density[i] = (y0 * (x - 1) * (x - 2) / 2 - y1 * x * (x - 2) + y2 * x * (x - 1) / 2)
                    else:
                        w = 0.25 if k == 0 else 0.5
                        density[i] = (1 - w) * even[k] + w * even[k + 1]
            return original(medium, sizes, transmittance, density, block)

        compute_module.multiple_scattering = patched
        sizes = dict(TABLE_SIZES, scattering_r=31)
        t = time.process_time()
        atm = PrecomputedAtmosphere.compute(p, orders=6, wavelengths=[550.0], sizes=sizes, progress=False)
        cpu = time.process_time() - t
        compute_module.multiple_scattering = original
        out = []
        for j, side in enumerate((1.0, -1.0)):
            d = np.stack([side * np.sin(VIEW_ZENITH), 0 * VIEW_ZENITH, np.cos(VIEW_ZENITH)], axis=-1)
            ours = atm.sky_radiance([0.0, 0.0, p.bottom_radius], d, sun)[:, 0]
            out.append(" ".join(f"{e:+.2f}" for e in 100 * (ours / ref[:, j] - 1)))
        print(f"31 rows, density replaced: {name} ({args.interp}), CPU {cpu:.1f} s; towards {out[0]} | away {out[1]}",
              flush=True)


if __name__ == "__main__":
    main()
