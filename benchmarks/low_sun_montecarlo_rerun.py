"""Rerun of a few stored low-sun Monte Carlo directions with another seed and more paths (docs/accuracy.md, "Low
sun"): is the stored reference of ``tests/data/low_sun_montecarlo.json`` converged there?

:func:`skyscatter.montecarlo.sky_radiance` (synchronous scheduler: one core) for one atmosphere and sun elevation of
the stored file, the given views, 400/560/700 nm; prints the new values with their standard errors and the stored
values' relative difference from them. The stored cases all use seed 1 and so share their random streams per
direction index: their errors are correlated across cases, and a rerun with another seed is the check.

``python benchmarks/low_sun_montecarlo_rerun.py [--atm aod05] [--sun 10] [--paths 262144] [--seed 11]
[--views 5/45,2/45,5/90,5/0]``
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.montecarlo import sky_radiance

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "low_sun_montecarlo.json"
ATMOSPHERES = {
    "earth": AtmosphereParameters,
    "turbidity3": lambda: AtmosphereParameters.from_turbidity(3.0),
    "aod05": lambda: AtmosphereParameters.from_aerosol_optical_depth(0.5),
}
WAVELENGTHS = [400.0, 560.0, 700.0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--atm", default="aod05", choices=sorted(ATMOSPHERES))
    ap.add_argument("--sun", type=float, default=10.0, help="sun elevation [deg], one of the stored")
    ap.add_argument("--paths", type=int, default=262144, help="paths per direction")
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--views", default="5/45,2/45,5/90,5/0", help="elev/az pairs [deg] of the stored views")
    args = ap.parse_args()
    views = [tuple(float(x) for x in v.split("/")) for v in args.views.split(",")]
    dirs = np.array([[math.cos(math.radians(e)) * math.sin(math.radians(a)),
                      math.cos(math.radians(e)) * math.cos(math.radians(a)), math.sin(math.radians(e))]
                     for e, a in views])
    t0 = time.process_time()
    mc = sky_radiance(ATMOSPHERES[args.atm](), dirs, WAVELENGTHS, sun_zenith=math.radians(90.0 - args.sun),
                      sun_azimuth=0.0, samples=args.paths, seed=args.seed, scheduler="synchronous")
    doc = json.loads(DATA.read_text())
    case = next(c for c in doc["cases"] if c["atmosphere"] == args.atm and c["sun_elevation_deg"] == args.sun)
    cols = [doc["wavelengths_nm"].index(w) for w in WAVELENGTHS]
    print(f"# {args.atm}, sun {args.sun:+g} deg, {mc.samples} paths, seed {args.seed}, "
          f"{time.process_time() - t0:.0f} CPU-s; 400 / 560 / 700 nm")
    print("| view elev/az [deg] | new MC [W m^-2 sr^-1 nm^-1] | new stderr [%] | stored / new - 1 [%] "
          "| stored stderr [%] |")
    print("|---|---|---|---|---|")
    for i, (e, a) in enumerate(views):
        j = doc["views_deg"].index([e, a])
        st = np.array(case["radiance"])[j, cols]
        sse = np.array(case["radiance_stderr"])[j, cols]
        new = mc.radiance[i]
        print(f"| {e:g}/{a:g} | " + " / ".join(f"{x:.4e}" for x in new) + " | "
              + " / ".join(f"{100 * s / x:.1f}" for s, x in zip(mc.stderr[i], new, strict=True)) + " | "
              + " / ".join(f"{100 * (s / x - 1):+.1f}" for s, x in zip(st, new, strict=True)) + " | "
              + " / ".join(f"{100 * s / x:.1f}" for s, x in zip(sse, st, strict=True)) + " |")


if __name__ == "__main__":
    main()
