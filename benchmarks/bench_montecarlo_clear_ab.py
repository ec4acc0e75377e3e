"""Throughput of the Monte Carlo kernels against an older commit's, alternating in one process: clear sky, overcast.

The older ``src/skyscatter`` is extracted (``git archive``) into a temporary folder as the package
``skyscatter_old`` (its imports are relative) and both run the same job in turn: Earth defaults, 11 wavelengths
360-760 nm, sun 20 deg above the horizon, 50 equal-area directions x 2048 paths, one thread (synchronous
scheduler). Prints the best, second best and median paths per CPU-second of each, their ratios and the largest
relative difference of the radiances. Default commit 663eefd: the kernels before the clouds (issue 21).
Usage: ``python benchmarks/bench_montecarlo_clear_ab.py [--commit REV] [--also REV] [--runs N] [--overcast]``; run
from the repository. ``--also REV``: a third package (``skyscatter_also``, e.g. ``main``) alternated with the two in
every round (clear sky), with its ratios and whether the working tree's radiances equal its to the bit. The packages
take turns at running first in a round.
``--overcast``: the pilot of ``bench_montecarlo.py --overcast`` instead (issue 21's layer of optical depth
15, Mie droplets r_e 10 um at 1000-1500 m, sun zenith 60 deg, 20 of the 200 views, 4096 paths, seed 1 + run):
paths per CPU-second, events per path, per-path relative standard deviation (median), efficiency 1 / (variance x
CPU time), the minutes a 1 % median standard error takes on 2 cores, and per run the z-scores of new against old.
The old package is compiled in the process every time; delete the tree's numba cache (``find src -name
'*.nb[ic]' -delete``) first, so the working tree's kernels are too: a kernel loaded from the cache ran some 5 %
slower than the same kernel compiled in the process (docs/clouds.md, "Speed").
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

from skyscatter.montecarlo import sky_radiance
from skyscatter.montecarlo.dataset import equal_area_directions

WAVELENGTHS = np.arange(360.0, 761.0, 40.0)
SUN_ZENITH = math.radians(70.0)


def _old_package(commit: str, root: Path, overcast: bool, name: str = "skyscatter_old"):
    repo = Path(__file__).resolve().parents[1]
    archive = subprocess.run(["git", "-C", str(repo), "archive", commit, "src/skyscatter"], check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(root)], input=archive, check=True)
    shutil.move(str(root / "src" / "skyscatter"), str(root / name))
    shutil.rmtree(root / "src")
    if str(root) not in sys.path:
        sys.path.insert(0, str(root))
    return _atmosphere(name, overcast), importlib.import_module(name + ".montecarlo").sky_radiance


def _atmosphere(package: str, overcast: bool):
    """The Earth defaults of ``package``, under the overcast layer with ``overcast``."""
    atm = importlib.import_module(package + ".atmosphere").AtmosphereParameters()
    if not overcast:
        return atm
    layer = importlib.import_module(package + ".atmosphere.clouds").CloudLayer
    return atm.replace(particles=(layer(1000.0, 1500.0, 15.0, effective_radius=10e-6),))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--commit", default="663eefd")
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--overcast", action="store_true")
    ap.add_argument("--also", default=None, help="a third package (e.g. main) alternated with the two (clear sky)")
    args = ap.parse_args()
    oc = args.overcast
    dirs = equal_area_directions(200)[::10] if oc else equal_area_directions(1000)[::20]
    sun_zenith, samples = (math.radians(60.0), 4096) if oc else (SUN_ZENITH, 2048)
    with tempfile.TemporaryDirectory() as tmp:
        impl = {"old": _old_package(args.commit, Path(tmp), oc)}
        if args.also and not oc:
            impl["also"] = _old_package(args.also, Path(tmp), oc, "skyscatter_also")
        impl["new"] = (_atmosphere("skyscatter", oc), sky_radiance)
        for atm, fn in impl.values():
            fn(atm, dirs[:2], WAVELENGTHS, sun_zenith=sun_zenith, samples=8, scheduler="synchronous")  # compile
        print(f"load average {os.getloadavg()[0]:.1f} at start")
        rates: dict[str, list[float]] = {k: [] for k in impl}
        rad = {}
        names = list(impl)
        for run in range(args.runs):
            for name in names[run % len(names):] + names[:run % len(names)]:  # each first in turn (order effects)
                atm, fn = impl[name]
                c0 = time.process_time()
                r = fn(atm, dirs, WAVELENGTHS, sun_zenith=sun_zenith, samples=samples, scheduler="synchronous",
                       seed=1 + run if oc else 1)
                rate = dirs.shape[0] * r.samples / (time.process_time() - c0)
                rates[name].append(rate)
                rad[name] = r
                if oc:
                    sd = float(np.median(r.relative_stderr)) * math.sqrt(r.samples)
                    print(f"run {run} {name}: {rate:,.0f} paths per CPU-second, {r.mean_vertices:.1f} events per path, "
                          f"per-path relative std {sd:.2f}, efficiency {rate / sd**2:,.0f}, 1 % median standard error "
                          f"{200 * (sd / 0.01) ** 2 / rate / 120:.1f} min on 2 cores (load {os.getloadavg()[0]:.1f})")
            if oc:
                z = (rad["new"].radiance - rad["old"].radiance) / np.hypot(rad["new"].stderr, rad["old"].stderr)
                print(f"run {run}: z new - old: mean {z.mean():+.2f}, std {z.std():.2f}, largest |z| "
                      f"{np.abs(z).max():.2f} ({z.size} values; the runs share seeds, so the z spread is below 1)")
        if oc:
            return
    per_round = {k: np.median([a / b for a, b in zip(v, rates["old"], strict=True)]) for k, v in rates.items()}
    labels = {"old": args.commit, "also": args.also, "new": "working tree"}
    for name, v in rates.items():
        v.sort()
        print(f"{name} ({labels[name]}): best {v[-1]:,.0f}, second {v[-2]:,.0f}, median {np.median(v):,.0f} paths per "
              f"CPU-second; per-round median ratio to old {per_round[name]:.3f}")
    if "also" in rates:
        a = rates["also"]
        print(f"also / old: best {a[-1] / rates['old'][-1]:.3f}, median {np.median(a) / np.median(rates['old']):.3f}; "
              f"new / also: best {rates['new'][-1] / a[-1]:.3f}, median {np.median(rates['new']) / np.median(a):.3f}; "
              f"radiances new against also identical: {np.array_equal(rad['new'].radiance, rad['also'].radiance)}, "
              f"standard errors: {np.array_equal(rad['new'].stderr, rad['also'].stderr)}")
    print(f"new / old: best {rates['new'][-1] / rates['old'][-1]:.3f}, median "
          f"{np.median(rates['new']) / np.median(rates['old']):.3f}; radiances: largest relative difference "
          f"{np.max(np.abs(rad['new'].radiance / rad['old'].radiance - 1)):.1e}; load average "
          f"{os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
