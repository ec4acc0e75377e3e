"""The Monte Carlo reference's single scattering at low sun (tests/data/low_sun_single_montecarlo.json; the test of
the observer's single scattering in twilight, tests/test_precomputed_low_sun.py; docs/accuracy.md, "Low sun").

The cases of ``benchmarks/low_sun_montecarlo_reference.py`` (three atmospheres, sun elevations +10, +3, 0, -3,
-6, -2.3 and -5.1 deg at azimuth 0, an observer on the ground, its 15 view directions) at 400, 560 and 700 nm, the
first order of scattering alone: :func:`skyscatter.montecarlo.sky_radiance` with ``orders=1`` (each path ends after
its first vertex; the solar disc sampled uniformly, as for every order), 1048576 paths per direction, seed 31 in
every case (the cases' errors are therefore correlated across the suns; each case's own are independent between
directions). Made 2026-12-06 with ``nice python benchmarks/low_sun_single_reference.py --out
tests/data/low_sun_single_montecarlo.json`` (40-100 s per case on the shared 2 cores); the file is rewritten
atomically after each case and cases already in it are skipped.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from low_sun_montecarlo_reference import ATMOSPHERES, CASE_ORDER, directions, views  # noqa: E402  (a sibling)
from skyscatter.fileio import atomic_path
from skyscatter.montecarlo import sky_radiance

WAVELENGTHS = [400.0, 560.0, 700.0]
PATHS = 1048576
SEED = 31


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args()
    doc = json.loads(args.out.read_text()) if args.out.exists() else {
        "description": "Monte Carlo single scattering (orders=1) at low sun seen from the ground "
                       "(skyscatter.montecarlo.sky_radiance), the cases of tests/data/low_sun_montecarlo.json",
        "generator": "benchmarks/low_sun_single_reference.py", "wavelengths_nm": WAVELENGTHS,
        "views_deg": views(), "sun_azimuth_deg": 0.0, "observer_altitude_m": 0.0, "orders": 1,
        "atmospheres": {k: v[0] for k, v in ATMOSPHERES.items()}, "cases": []}
    done = {(c["atmosphere"], c["sun_elevation_deg"]) for c in doc["cases"]}
    for name, sun in CASE_ORDER:
        if (name, sun) in done:
            continue
        t0 = time.perf_counter()
        mc = sky_radiance(ATMOSPHERES[name][1](), directions(), WAVELENGTHS, sun_zenith=math.radians(90.0 - sun),
                          samples=PATHS, seed=SEED, orders=1)
        doc["cases"].append({"atmosphere": name, "sun_elevation_deg": sun, "paths": int(mc.samples), "seed": SEED,
                             "radiance": np.asarray(mc.radiance).tolist(),
                             "radiance_stderr": np.asarray(mc.stderr).tolist(),
                             "seconds": round(time.perf_counter() - t0, 1)})
        with atomic_path(args.out) as tmp:
            Path(tmp).write_text(json.dumps(doc, indent=1) + "\n")
        print(f"{name} {sun:+g} deg: {time.perf_counter() - t0:.0f} s", flush=True)


if __name__ == "__main__":
    main()
