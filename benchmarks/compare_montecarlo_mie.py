"""Precomputed tables with a tabulated Mie aerosol vs the Monte Carlo reference (issue 20, "Checks").

OPAC continental-average and maritime-clean at aerosol optical depth 0.2 (550 nm), ground albedo 0.1, sun zenith 30
deg; radiance at the ground in the principal plane, view zenith 0-70 deg on both sides; tables with the sizes of
tests/test_precomputed_disort.py and 6 orders; the Monte Carlo (which samples the full phase table) with 16384 paths
per direction. Prints the relative difference and the Monte Carlo's standard error.

    PYTHONPATH=src python benchmarks/compare_montecarlo_mie.py
"""

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.montecarlo.driver import sky_radiance  # noqa: E402
from skyscatter.precomputed import PrecomputedAtmosphere  # noqa: E402
from test_precomputed_disort import SIZES  # noqa: E402


def main() -> None:
    vz = np.radians(np.arange(0.0, 71.0, 10.0))
    ts = math.radians(30.0)
    print("| type | side | tables / MC - 1 at view zenith 0, 10, ..., 70 deg [%] | MC stderr max [%] |")
    print("|---|---|---|---|")
    for name in ("continental-average", "maritime-clean"):
        p = AtmosphereParameters.with_aerosol_type(name, 0.2, 50.0, ground_albedo=0.1)
        atm = PrecomputedAtmosphere.compute(p, orders=6, wavelengths=[550.0], sizes=SIZES, progress=False)
        for side, label in ((1.0, "towards sun"), (-1.0, "away")):
            d = np.stack([side * np.sin(vz), 0 * vz, np.cos(vz)], axis=-1)
            keep = np.abs(np.degrees(vz) * side - 30.0) > 5.0  # not the sun itself
            ours = atm.sky_radiance([0.0, 0.0, p.bottom_radius], d, [math.sin(ts), 0.0, math.cos(ts)])[:, 0]
            mc = sky_radiance(p, d, [550.0], sun_zenith=ts, sun_azimuth=math.pi / 2, samples=16384, seed=5)
            # directions are ENU with the sun's azimuth 90 deg (east, +x)
            err = 100 * (ours / mc.radiance[:, 0] - 1)
            cells = " ".join(f"{e:+.1f}" if k else "(sun)" for e, k in zip(err, keep, strict=True))
            print(f"| {name} | {label} | {cells} | {100 * np.max(mc.relative_stderr):.1f} |", flush=True)


if __name__ == "__main__":
    main()
