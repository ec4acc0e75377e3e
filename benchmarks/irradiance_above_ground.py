"""The tables' diffuse irradiance on a horizontal surface ABOVE the ground against DISORT.

The irradiance table ([Bruneton2008] Eq. 15) has radius rows linear in the altitude (16 over 60 km, 4 km apart at
the default sizes), so between the ground and 4 km it interpolates across an aerosol's 1.2 km scale height. This
compares, at 0, 500, 1500 and 3000 m, sun zenith 30 / 60 / 80 deg, 405 / 480 / 555 / 655 nm, default table sizes:

* ``table``: the stored table read (``TableLookups.table_irradiance``, what ``ground_irradiance`` returned
  everywhere before 2026-12-04);
* ``integral``: the tables' sky radiance (Eq. 16) integrated over the upper hemisphere on the quadrature of
  ``ground_irradiance`` above the ground (``TableLookups.sky_irradiance_integral``), and the same on a finer
  quadrature (its own quadrature error);

against DISORT's diffuse down-flux at the same altitude (disortpp, plane-parallel, 32 streams, 300 layers;
``tests/disort_reference.py``) for the Earth air and aerosol optical depths 0.1 and 0.5 (Angstrom 1.3, scale height
1.2 km, Cornette-Shanks g 0.8; ground albedo of the defaults). Also the CPU time of each per (point, sun).

    PYTHONPATH=src python benchmarks/irradiance_above_ground.py
"""

import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from disort_reference import disort_diffuse_irradiance  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.precomputed import PrecomputedAtmosphere  # noqa: E402

WL = np.array([405.0, 480.0, 555.0, 655.0])
ALTITUDES = (0.0, 500.0, 1500.0, 3000.0)
SUN_ZENITH_DEG = (30.0, 60.0, 80.0)


def airs() -> dict[str, AtmosphereParameters]:
    return {"Earth": AtmosphereParameters(),
            "AOD 0.1": AtmosphereParameters.from_aerosol_optical_depth(0.1),
            "AOD 0.5": AtmosphereParameters.from_aerosol_optical_depth(0.5)}


def main() -> None:
    print(f"load average {os.getloadavg()[0]:.1f}")
    print("air | altitude m | sun zenith | DISORT 405/655 | table vs DISORT [%] | integral [%] | fine integral [%]")
    cost: dict[str, list[float]] = {"table": [], "integral": [], "fine": []}
    worst: dict[str, float] = {"table": 0.0, "integral": 0.0, "fine": 0.0}
    for name, air in airs().items():
        atm = PrecomputedAtmosphere.compute(air, wavelengths=WL, progress=False)
        esun = air.solar_irradiance_at(WL)
        up = np.array([0.0, 0.0, 1.0])
        for h in ALTITUDES:
            pos = np.array([0.0, 0.0, air.bottom_radius + h])
            for sz in SUN_ZENITH_DEG:
                sun = np.array([math.sin(math.radians(sz)), 0.0, math.cos(math.radians(sz))])
                ref = esun * np.array([disort_diffuse_irradiance(air, w, math.radians(sz), altitude=h, n_layers=300)
                                       for w in WL])
                got = {}
                t0 = time.process_time()
                got["table"] = atm.table_irradiance(pos, up, sun)[1]
                t1 = time.process_time()
                got["integral"] = atm.sky_irradiance_integral(pos, sun)
                t2 = time.process_time()
                got["fine"] = atm.sky_irradiance_integral(pos, sun, nodes=32, azimuth_step=0.5)
                t3 = time.process_time()
                for k, dt in (("table", t1 - t0), ("integral", t2 - t1), ("fine", t3 - t2)):
                    cost[k].append(dt)
                err = {k: 100.0 * (np.ravel(v) / ref - 1.0) for k, v in got.items()}
                for k, e in err.items():
                    worst[k] = max(worst[k], float(np.abs(e).max())) if h > 0 else worst[k]
                print(f"{name} | {h:.0f} | {sz:.0f} | {ref[0] / esun[0]:.4f}/{ref[-1] / esun[-1]:.4f} | "
                      + " | ".join(" ".join(f"{x:+.1f}" for x in err[k]) for k in ("table", "integral", "fine")),
                      flush=True)
    print("worst |error| above the ground [%]: " + ", ".join(f"{k} {v:.1f}" for k, v in worst.items()))
    print("CPU per (point, sun), median of the calls after the first [ms]: "
          + ", ".join(f"{k} {1e3 * float(np.median(v[1:])):.2f}" for k, v in cost.items()))


if __name__ == "__main__":
    main()
