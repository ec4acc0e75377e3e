"""Throughput of the Monte Carlo kernels with and without ``skyscatter.jit``'s binding of ``exp`` and ``log``, in one
process, alternating.

The binding (``jit._bind_libm``: glibc's ``__exp_finite`` / ``__log_finite`` instead of the wrapper numba binds) is made
for the whole process when ``skyscatter.jit`` is imported, and a compiled function's calls are bound when it is
finalised. So the older package of ``--commit`` (extracted with ``git archive`` as ``skyscatter_old``, as in
``bench_montecarlo_clear_ab.py``) is imported, and its kernels compiled, *before* this tree's package: they keep numba's
binding, and the two then run the same job in turn (``bench_montecarlo_clear_ab.py`` imports this tree first, so both of
its packages have the binding). Prints per run the paths per CPU-second, events per path, per-path relative standard
deviation and efficiency of each and whether the radiances and standard errors are identical; then best and median.
Usage: ``python benchmarks/bench_libm_binding_ab.py [--commit REV] [--runs N] [--clear]``; run from the repository
with this tree first on PYTHONPATH. The overcast pilot (layer of optical depth 15, Mie droplets r_e 10 um at 1000-1500
m, sun zenith 60 deg, 20 of 200 views, 4096 paths, seed 1 + run), or ``--clear`` the clear sky (Earth defaults, sun
20 deg high, 50 views x 2048 paths).
"""

from __future__ import annotations

import argparse
import importlib
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

WAVELENGTHS = np.arange(360.0, 761.0, 40.0)


def _setup(package: str, overcast: bool):
    atm = importlib.import_module(package + ".atmosphere").AtmosphereParameters()
    if overcast:
        layer = importlib.import_module(package + ".atmosphere.clouds").CloudLayer
        atm = atm.replace(particles=(layer(1000.0, 1500.0, 15.0, effective_radius=10e-6),))
    return atm, importlib.import_module(package + ".montecarlo").sky_radiance


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--commit", default="main")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--clear", action="store_true")
    args = ap.parse_args()
    oc = not args.clear
    repo = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(["git", "-C", str(repo), "archive", args.commit, "src/skyscatter"], check=True,
                                 capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        shutil.move(os.path.join(tmp, "src", "skyscatter"), os.path.join(tmp, "skyscatter_old"))
        sys.path.insert(0, tmp)
        dirs = importlib.import_module("skyscatter_old.montecarlo.dataset").equal_area_directions(200 if oc else 1000)
        dirs = dirs[::10] if oc else dirs[::20]
        sz, samples = (math.radians(60.0), 4096) if oc else (math.radians(70.0), 2048)
        impl = {"old": _setup("skyscatter_old", oc)}
        impl["old"][1](impl["old"][0], dirs[:2], WAVELENGTHS, sun_zenith=sz, samples=8, scheduler="synchronous")
        impl["new"] = _setup("skyscatter", oc)  # imports skyscatter.jit: the binding, for what is compiled from now on
        impl["new"][1](impl["new"][0], dirs[:2], WAVELENGTHS, sun_zenith=sz, samples=8, scheduler="synchronous")
        bound = importlib.import_module("skyscatter.jit").LIBM_BINDINGS
        print(f"bound: {sorted(bound)}; load average {os.getloadavg()[0]:.1f} at start")
        rates: dict[str, list[float]] = {k: [] for k in impl}
        for run in range(args.runs):
            rad = {}
            for name, (atm, fn) in impl.items():
                c0 = time.process_time()
                r = fn(atm, dirs, WAVELENGTHS, sun_zenith=sz, samples=samples, scheduler="synchronous",
                       seed=1 + run if oc else 1)
                rate = dirs.shape[0] * r.samples / (time.process_time() - c0)
                rates[name].append(rate)
                rad[name] = r
                sd = float(np.median(r.relative_stderr)) * math.sqrt(r.samples)
                print(f"run {run} {name}: {rate:,.0f} paths per CPU-second, {r.mean_vertices:.1f} events per path, "
                      f"per-path relative std {sd:.2f}, efficiency {rate / sd**2:,.0f} (load {os.getloadavg()[0]:.1f})",
                      flush=True)
            same = (np.array_equal(rad["new"].radiance, rad["old"].radiance)
                    and np.array_equal(rad["new"].stderr, rad["old"].stderr))
            print(f"run {run}: new / old {rates['new'][-1] / rates['old'][-1]:.3f}; radiances and standard errors "
                  f"identical: {same}")
    for name, v in rates.items():
        print(f"{name}: best {max(v):,.0f}, median {np.median(v):,.0f} paths per CPU-second")
    print(f"new / old: best {max(rates['new']) / max(rates['old']):.3f}, median "
          f"{np.median(rates['new']) / np.median(rates['old']):.3f}; load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
