"""The tables' radiance at low sun against the stored Monte Carlo values by number of orders (docs/accuracy.md,
"Low sun"): where in the orders the tables' excess over the Monte Carlo comes from.

For one atmosphere, sun elevation and wavelength of ``tests/data/low_sun_montecarlo.json``, the tables computed with
1, 2, 3, ... orders (from 3 orders on with the geometric tail of the orders after the last) and each one's
``100 (tables / MC - 1)`` per stored view direction. With ``benchmarks/second_order_low_sun.py`` (the second order
alone against an independent integral) this separates the second order from the orders after it.

``python benchmarks/low_sun_orders.py [--atm turbidity3] [--sun=-6] [--wavelength 560] [--orders 1,2,3,4,6,9]``
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from skyscatter.precomputed import AtmosphereParameters, PrecomputedAtmosphere

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "low_sun_montecarlo.json"
ATMOSPHERES = {
    "earth": AtmosphereParameters,
    "turbidity3": lambda: AtmosphereParameters.from_turbidity(3.0),
    "aod05": lambda: AtmosphereParameters.from_aerosol_optical_depth(0.5),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--atm", default="turbidity3", choices=sorted(ATMOSPHERES))
    ap.add_argument("--sun", type=float, default=-6.0, help="sun elevation [deg], one of the stored")
    ap.add_argument("--wavelength", type=float, default=560.0, help="[nm], one of the stored")
    ap.add_argument("--orders", default="1,2,3,4,6,9")
    args = ap.parse_args()
    doc = json.loads(DATA.read_text())
    case = next(c for c in doc["cases"] if c["atmosphere"] == args.atm and c["sun_elevation_deg"] == args.sun)
    col = doc["wavelengths_nm"].index(args.wavelength)
    views = doc["views_deg"]
    dirs = np.array([[math.cos(math.radians(e)) * math.sin(math.radians(a)),
                      math.cos(math.radians(e)) * math.cos(math.radians(a)), math.sin(math.radians(e))]
                     for e, a in views])
    s = math.radians(args.sun)
    sun = np.array([0.0, math.cos(s), math.sin(s)])
    params = ATMOSPHERES[args.atm]()
    pos = np.array([0.0, 0.0, params.bottom_radius])
    mc = np.array(case["radiance"])[:, col]
    se = np.array(case["radiance_stderr"])[:, col]
    orders = [int(n) for n in args.orders.split(",")]
    res = {}
    t0 = time.process_time()
    for n in orders:
        atm = PrecomputedAtmosphere.compute(params, orders=n, wavelengths=[args.wavelength], progress=False)
        res[n] = atm.sky_radiance(pos, dirs, sun)[:, 0]
    print(f"# {args.atm}, sun {args.sun:+g} deg, {args.wavelength:g} nm; tables {time.process_time() - t0:.0f} CPU-s; "
          "cells 100 (tables / MC - 1) [%]")
    print("| view elev/az [deg] | MC [W m^-2 sr^-1 nm^-1] | MC stderr [%] | "
          + " | ".join(f"{n} orders" for n in orders) + " |")
    print("|---|---|---|" + "---|" * len(orders))
    for i, (e, a) in enumerate(views):
        print(f"| {e:g}/{a:g} | {mc[i]:.3e} | {100 * se[i] / mc[i]:.1f} | "
              + " | ".join(f"{100 * (res[n][i] / mc[i] - 1):+.1f}" for n in orders) + " |")


if __name__ == "__main__":
    main()
