"""Sky radiance of full tables (4 orders, default sizes, 450/550/650 nm, the default air and the continental-average
Mie air) from 0 m, 10 m, 150 m and 2 km over 45 directions and two suns, saved to an .npz: run it on two versions of
the code and compare with ``--compare A.npz B.npz`` (max / median relative change per altitude).

Run: PYTHONPATH=src python benchmarks/r_interpolation_sky_change.py OUT.npz
"""

from __future__ import annotations

import math
import sys

import numpy as np

HEIGHTS = (0.0, 10.0, 150.0, 2000.0)


def sky(out):
    from skyscatter.atmosphere import AtmosphereParameters
    from skyscatter.precomputed import PrecomputedAtmosphere

    dirs = []
    for el in (-10.0, -3.0, 2.0, 5.0, 10.0, 20.0, 40.0, 70.0, 90.0):
        for az in (0.0, 45.0, 90.0, 135.0, 180.0):
            e, a = math.radians(el), math.radians(az)
            dirs.append((math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)))
    dirs = np.array(dirs)
    res = {}
    airs = {"default": AtmosphereParameters(),
            "mie": AtmosphereParameters.with_aerosol_type("continental-average", 0.2, 50.0)}
    for name, p in airs.items():
        atm = PrecomputedAtmosphere.compute(p, orders=4, wavelengths=[450.0, 550.0, 650.0], progress=False)
        for sz in (30.0, 75.0):
            ts = math.radians(sz)
            sun = np.array([math.sin(ts), 0.0, math.cos(ts)])
            for h in HEIGHTS:
                res[f"{name}_{sz:.0f}_{h:.0f}"] = atm.sky_radiance([0.0, 0.0, p.bottom_radius + h], dirs, sun)
    np.savez(out, **res)


def compare(a, b):
    da, db = np.load(a), np.load(b)
    for k in da.files:
        ch = 100 * np.abs(db[k] / da[k] - 1.0)
        print(f"{k:18s}: |change| max {ch.max():6.3f} % median {np.median(ch):6.3f} %")


if __name__ == "__main__":
    if sys.argv[1] == "--compare":
        compare(sys.argv[2], sys.argv[3])
    else:
        sky(sys.argv[1])
