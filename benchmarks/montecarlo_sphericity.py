"""How far the Earth's sky is from the plane-parallel limit: Monte Carlo on the Earth (R = 6360 km) against the
same atmosphere on a planet 1000x larger (the plane-parallel limit that DISORT solves), principal plane, 500 nm.

Prints ``earth / flat - 1`` [%] and the combined standard error per view zenith, for the DISORT test cases
(pure Rayleigh and Rayleigh + aerosol tau 0.1, albedo 0.1, sun zenith 30 and 70 deg).
Usage: ``python benchmarks/montecarlo_sphericity.py [--samples N]``.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from skyscatter.montecarlo import sky_radiance
from skyscatter.precomputed import AtmosphereParameters

VIEW = [0.0, 40.0, 60.0, 80.0, 85.0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=8192)
    args = ap.parse_args()
    dirs = []
    for side in (1.0, -1.0):
        for z in VIEW:
            zr = math.radians(z)
            dirs.append([0.0, side * math.sin(zr), math.cos(zr)])
    dirs = np.array(dirs)
    print("| case | sun zenith | " + " | ".join(f"{s}{z:.0f}" for s in ("+", "-") for z in VIEW) + " |")
    print("|---|---|" + "---|" * len(dirs))
    for beta in (0.0, 0.1):
        for sz in (30.0, 70.0):
            out = []
            for radius in (6.36e6, 6.36e9):
                atm = AtmosphereParameters(bottom_radius=radius, top_radius=radius + 60e3, ozone_column=0.0,
                                           mie_angstrom_beta=beta, ground_albedo=0.1, solar_irradiance=1.0,
                                           mie_phase_function="henyey-greenstein")
                out.append(sky_radiance(atm, dirs, [500.0], sun_zenith=math.radians(sz), samples=args.samples,
                                        seed=3))
            e, f = out
            rel = 100 * (e.radiance[:, 0] / f.radiance[:, 0] - 1)
            err = 100 * np.hypot(e.stderr[:, 0] / e.radiance[:, 0], f.stderr[:, 0] / f.radiance[:, 0])
            name = "Rayleigh" if beta == 0 else "Rayleigh + aerosol 0.1"
            print(f"| {name} | {sz:.0f} | " + " | ".join(f"{r:+.1f}±{s:.1f}" for r, s in zip(rel, err, strict=True))
                  + " |")
    print("\ncolumns: + towards the sun, - away, view zenith [deg]; cells: 100 (Earth / plane-parallel - 1) "
          "± combined standard error [%]")


if __name__ == "__main__":
    main()
