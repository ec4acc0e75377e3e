"""Single scattering of the precomputed tables near the ground against the independent integral.

The 4D tables sample altitude as rho = sqrt(r^2 - R_g^2) (Bruneton & Neyret 2008, Sec. 4): the first row above
the ground is at 62.5 m (default 32 rows). Since table format 16 the ground cell's rows are each read at their own
``mu`` coordinate and weighted in the altitude where that cell ends below 300 m (``ALTITUDE_LINEAR_CELL_TOP``).

Single-scattering tables (orders=1, default sizes, 450 and 650 nm) of the continental-average Mie aerosol of
tests/test_precomputed_mie.py and of the default air (Cornette-Shanks), sun at 30 and 75 deg zenith, views at the
elevations ELEVATIONS [deg] and azimuth 0-180 deg, from the altitudes HEIGHTS [m]; the radiance without the ground
against the brute-force integral of tests/precomputed_reference.py. Both rendering paths: the general 4D kernel
(one position per ray) and the observer slices (one position). Prints the worst and median |error| [%] per air,
sun, height, path and part (rays into the sky; rays towards the ground, from above the ground only) and writes
them as JSON to $OUT if set.

Defaults: ELEVATIONS="2 3 5 7 10 15 20 30", HEIGHTS="0 10 30 62 150" (the views of docs/aerosols.md's format 15 ->
16 table); the whole sphere of its rho-weight table: ELEVATIONS="-10 -3 2 5 10 20 40 70 90" HEIGHTS="10 30 150
400 780".
Run: PYTHONPATH=src:tests python benchmarks/r_interpolation_near_ground.py
"""

from __future__ import annotations

import json
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
HEIGHTS = tuple(float(h) for h in os.environ.get("HEIGHTS", "0 10 30 62 150").split())
ELEVATIONS = tuple(float(e) for e in os.environ.get("ELEVATIONS", "2 3 5 7 10 15 20 30").split())


def directions():
    out = []
    for el in ELEVATIONS:
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
    results = {}
    for name, p in airs.items():
        atm = PrecomputedAtmosphere.compute(p, orders=1, wavelengths=WL, progress=False)
        for sun_zen in (30.0, 75.0):
            ts = math.radians(sun_zen)
            sun = np.array([math.sin(ts), 0.0, math.cos(ts)])
            for h in HEIGHTS:
                r = p.bottom_radius + h
                pos = np.array([0.0, 0.0, r])
                ref = np.array([single_scattering(r, float(d[2]), math.cos(ts), float(d @ sun), p, WL) for d in dirs])
                paths = {"4d": atm.sky_radiance(np.broadcast_to(pos, dirs.shape), dirs, sun, include_ground=False),
                         "observer": atm.sky_radiance(pos, dirs, sun, include_ground=False)}
                for path, ours in paths.items():
                    err = np.abs(100 * (ours / ref - 1.0))
                    for part, keep in (("sky", dirs[:, 2] > 0), ("ground", dirs[:, 2] < 0)):
                        if not keep.any() or (h == 0.0 and part == "ground"):
                            continue  # no ray from the ground into it
                        e, d = err[keep], dirs[keep]
                        worst = int(np.argmax(e.max(axis=1)))
                        key = f"{name} sun {sun_zen:.0f} h {h:g} {path} {part}"
                        results[key] = [float(e.max()), float(np.median(e))]
                        print(f"{key:37s}: |err| max {e.max():5.2f} % (el {np.degrees(np.arcsin(d[worst, 2])):5.1f}"
                              f" az {np.degrees(np.arctan2(d[worst, 1], d[worst, 0])):5.1f}) median "
                              f"{np.median(e):5.2f} %", flush=True)
    print(f"CPU {time.process_time() - t0:.0f} s")
    if os.environ.get("OUT"):
        with open(os.environ["OUT"], "w", encoding="utf-8") as fh:
            json.dump(results, fh, indent=1)


if __name__ == "__main__":
    main()
