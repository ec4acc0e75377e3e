"""Speed targets of issue 20: Mie tables, the precompute with a tabulated phase, a sky-scan retrieval.

1. Mie optics of a 16-wavelength (400-700 nm), 3-mode aerosol (OPAC continental-average: water-soluble,
   insoluble, soot) from a cold in-process cache, best of 3; the cached call; miepython's import (numba backend)
   measured apart.
2. The default precompute (16 wavelengths, default sizes and orders) with the default analytic aerosol and with
   the same optical depth as a tabulated Mie aerosol, alternated, best of 2 each: the ratio (target <= 1.2).
3. A sky-scan retrieval: 81 directions at 3 wavelengths (synthetic, tables of other sizes), optical depth, g and
   ground albedo free (target < 2 min on 2 cores).

``--processes N``: only section 2, as whole processes (a fresh interpreter per precompute, so neither numba's
in-process state nor a warm cache favours one side), analytic and tabulated alternated N times; each reports the
precompute's wall time and CPU time (both threads) and the process's wall time (imports, miepython's and the Mie
tables included, unless ``--mie-apart``: then the Mie tables are made before the precompute's clock starts); best
of N each and the ratios, with the load average.

    PYTHONPATH=src python benchmarks/bench_aerosols.py
    PYTHONPATH=src python benchmarks/bench_aerosols.py --processes 3 [--mie-apart]
"""

import argparse
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

_CHILD = """
import json, sys, time
t0 = time.perf_counter()
from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.precomputed import PrecomputedAtmosphere
if sys.argv[1] == "analytic":
    air = AtmosphereParameters.from_aerosol_optical_depth(0.2, 1.3)
else:
    air = AtmosphereParameters().with_aerosol_type("continental-average", 0.2)
    if len(sys.argv) > 2:  # the Mie tables (and miepython's import) first, outside the precompute's time
        air.aerosol_phase_table([400.0 + 20.0 * i for i in range(16)])
w, c = time.perf_counter(), time.process_time()
PrecomputedAtmosphere.compute(air, progress=False)
print(json.dumps({"compute": time.perf_counter() - w, "cpu": time.process_time() - c,
                  "before": w - t0}))
"""


def bench_processes(rounds: int, mie_apart: bool) -> None:
    """Section 2 as whole processes, alternated (module docstring); ``mie_apart``: the tabulated process makes its
    Mie tables before the precompute's clock starts (they are cached per process, and their own target is
    separate)."""
    print(f"load average at start: {os.getloadavg()}")
    runs: dict[str, list[dict[str, float]]] = {"analytic": [], "tabulated": []}
    for _ in range(rounds):
        for name in runs:
            t = time.perf_counter()
            cmd = [sys.executable, "-c", _CHILD, name] + (["mie-apart"] if mie_apart else [])
            out = subprocess.run(cmd, capture_output=True, text=True, check=True)
            r = json.loads(out.stdout.strip().splitlines()[-1])
            r["process"] = time.perf_counter() - t
            runs[name].append(r)
            print(f"  {name}: precompute {r['compute']:.1f} s wall, {r['cpu']:.1f} s CPU; process {r['process']:.1f} s"
                  f" (load {os.getloadavg()[0]:.1f})", flush=True)
    best = {n: {k: min(r[k] for r in rs) for k in ("compute", "cpu", "process")} for n, rs in runs.items()}
    for k in ("compute", "cpu", "process"):
        a, b = best["analytic"][k], best["tabulated"][k]
        print(f"{k}: analytic {a:.1f} s, tabulated {b:.1f} s (best of {rounds}), ratio {b / a:.2f}")
    print(f"load average at end: {os.getloadavg()}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--processes", type=int, default=0, metavar="N",
                    help="only the precompute ratio, as whole processes alternated N times")
    ap.add_argument("--mie-apart", action="store_true",
                    help="with --processes: the Mie tables made before the precompute's clock starts")
    args = ap.parse_args()
    if args.processes:
        bench_processes(args.processes, args.mie_apart)
        return
    print(f"load average at start: {os.getloadavg()}")
    t = time.perf_counter()
    from skyscatter.atmosphere.mie_optics import _mie_optics_cached, _miepython

    _miepython()
    print(f"miepython import (numba backend): {time.perf_counter() - t:.2f} s")
    from skyscatter.atmosphere.aerosol_types import OpacAerosol

    wl = np.linspace(400.0, 700.0, 16)
    aer = OpacAerosol.preset("continental-average", 0.2)
    aer.phase_table([550.0])  # compile and warm
    best = math.inf
    for _ in range(3):
        _mie_optics_cached.cache_clear()
        t = time.perf_counter()
        aer.phase_table(wl)
        aer.extinction_at(wl)
        best = min(best, time.perf_counter() - t)
    t = time.perf_counter()
    aer.phase_table(wl)
    cached = time.perf_counter() - t
    print(f"Mie tables, 16 wavelengths x 3 modes: {best:.2f} s cold (best of 3), {cached * 1e3:.1f} ms cached")

    from skyscatter.atmosphere import AtmosphereParameters
    from skyscatter.precomputed import PrecomputedAtmosphere

    analytic = AtmosphereParameters.from_aerosol_optical_depth(0.2, 1.3)
    tabulated = AtmosphereParameters(aerosol=aer)
    PrecomputedAtmosphere.compute(tabulated, wavelengths=[550.0], sizes=dict(scattering_r=4, scattering_mu=16,
                                                                              scattering_mu_s=8, scattering_nu=4),
                                  orders=2, progress=False)  # compile the tabulated paths
    times = {"analytic": [], "tabulated": []}
    for _ in range(2):
        for name, p in (("analytic", analytic), ("tabulated", tabulated)):
            t = time.perf_counter()
            PrecomputedAtmosphere.compute(p, progress=False)
            times[name].append(time.perf_counter() - t)
    a, b = min(times["analytic"]), min(times["tabulated"])
    print(f"default precompute: analytic {a:.1f} s, tabulated Mie {b:.1f} s (best of 2), ratio {b / a:.2f}; "
          f"all runs {times}")

    from skyscatter.conventions import direction_from_angles
    from skyscatter.fit.atmosphere import FIT_SIZES, SkyScan, fit_atmosphere

    true = AtmosphereParameters.from_aerosol_optical_depth(0.25, 1.3, mie_phase_g=0.7, ground_albedo=0.2)
    wl3 = np.array([440.0, 550.0, 670.0])
    zz, aa = np.meshgrid(np.radians(np.linspace(5.0, 80.0, 9)), np.radians(np.arange(0.0, 360.0, 40.0)))
    z, az = zz.ravel(), aa.ravel()
    sun = (math.radians(40.0), math.radians(180.0))
    atm = PrecomputedAtmosphere.compute(true, orders=6, wavelengths=wl3, progress=False,
                                        sizes=dict(FIT_SIZES, scattering_r=16, scattering_mu=64))
    values = atm.sky_radiance(np.array([0.0, 0.0, true.bottom_radius]), direction_from_angles(z, az),
                              direction_from_angles(*sun))
    t = time.perf_counter()
    fit = fit_atmosphere(SkyScan(z, az, values, *sun, wl3, 0.02))
    print(f"sky-scan retrieval (81 directions, 3 wavelengths, 3 free): {time.perf_counter() - t:.1f} s, "
          f"{fit.builds} table builds; {fit.values}")
    print(f"load average at end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
