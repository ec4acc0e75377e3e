"""Single scattering of the precomputed tables near the ground against the independent integral.

The 4D tables sample altitude as rho = sqrt(r^2 - R_g^2) (Bruneton & Neyret 2008, Sec. 4): the first row above
the ground is at 62.5 m (default 32 rows), and a lookup at 10 m falls 0.40 of the way into that cell in rho but
0.16 in height. This script compares ``sky_radiance`` of single-scattering tables (orders=1, default sizes, the
continental-average Mie aerosol of tests/test_precomputed_mie.py and the default Cornette-Shanks one) with the
brute-force integral of tests/precomputed_reference.py over many directions from several altitudes, and prints
the max / median relative error per altitude. Run: PYTHONPATH=src:tests python benchmarks/r_interpolation_near_ground.py
(altitudes [m]: HEIGHTS="0 10 ...")
"""

from __future__ import annotations

import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, "tests")
from precomputed_reference import single_scattering  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.precomputed import PrecomputedAtmosphere  # noqa: E402

WL = np.array([450.0, 650.0])
HEIGHTS = tuple(float(h) for h in os.environ.get("HEIGHTS", "0 10 30 62.5 150 2000").split())


def directions():
    out = []
    for el in (-10.0, -3.0, 2.0, 5.0, 10.0, 20.0, 40.0, 70.0, 90.0):
        for az in (0.0, 45.0, 90.0, 135.0, 180.0):
            e, a = math.radians(el), math.radians(az)
            out.append((math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)))
    return np.array(out)


def main():
    t0 = time.process_time()
    airs = {
        "mie": AtmosphereParameters.with_aerosol_type("continental-average", 0.2, 50.0, ozone_column=0.0,
                                                      solar_irradiance=1.0, ground_albedo=0.1),
        "default": AtmosphereParameters(ozone_column=0.0, solar_irradiance=1.0, ground_albedo=0.1),
    }
    dirs = directions()
    for name, p in airs.items():
        atm = PrecomputedAtmosphere.compute(p, orders=1, wavelengths=WL, progress=False)
        for sun_zen in (30.0, 75.0):
            ts = math.radians(sun_zen)
            sun = np.array([math.sin(ts), 0.0, math.cos(ts)])
            for h in HEIGHTS:
                r = p.bottom_radius + h
                ours = atm.sky_radiance([0.0, 0.0, r], dirs, sun, include_ground=False)
                ref = np.array([single_scattering(r, float(d[2]), math.cos(ts), float(d @ sun), p, WL) for d in dirs])
                err = 100 * (ours / ref - 1.0)
                for part, keep in (("sky", dirs[:, 2] > 0), ("ground", dirs[:, 2] < 0)):
                    if h == 0.0 and part == "ground":
                        continue  # no ray from the ground into it
                    a = np.abs(err[keep])
                    worst = np.argmax(a) // a.shape[1]
                    print(f"{name:8s} sun {sun_zen:4.0f} h {h:7.1f} m {part:6s}: |err| max {a.max():5.2f} % "
                          f"(el {np.degrees(np.arcsin(dirs[keep][worst, 2])):5.1f}) median {np.median(a):5.2f} % "
                          f"mean {err[keep].mean():+5.2f} %", flush=True)
    print(f"CPU {time.process_time() - t0:.0f} s")


if __name__ == "__main__":
    main()
