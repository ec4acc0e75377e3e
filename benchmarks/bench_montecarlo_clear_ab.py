"""Clear-sky throughput of the Monte Carlo kernels against an older commit's, alternating in one process.

The older ``src/skyscatter`` is extracted (``git archive``) into a temporary folder as the package
``skyscatter_old`` (its imports are relative) and both run the same job in turn: Earth defaults, 11 wavelengths
360-760 nm, sun 20 deg above the horizon, 50 equal-area directions x 2048 paths, one thread (synchronous
scheduler). Prints the best, second best and median paths per CPU-second of each, their ratios and the largest
relative difference of the radiances. Default commit 663eefd: the kernels before the clouds (issue 21).
Usage: ``python benchmarks/bench_montecarlo_clear_ab.py [--commit REV] [--runs N]``; run from the repository.
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

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.montecarlo import sky_radiance
from skyscatter.montecarlo.dataset import equal_area_directions

WAVELENGTHS = np.arange(360.0, 761.0, 40.0)
SUN_ZENITH = math.radians(70.0)


def _old_package(commit: str, root: Path):
    repo = Path(__file__).resolve().parents[1]
    archive = subprocess.run(["git", "-C", str(repo), "archive", commit, "src/skyscatter"], check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(root)], input=archive, check=True)
    shutil.move(str(root / "src" / "skyscatter"), str(root / "skyscatter_old"))
    sys.path.insert(0, str(root))
    atm = importlib.import_module("skyscatter_old.atmosphere")
    mc = importlib.import_module("skyscatter_old.montecarlo")
    return atm.AtmosphereParameters(), mc.sky_radiance


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--commit", default="663eefd")
    ap.add_argument("--runs", type=int, default=10)
    args = ap.parse_args()
    dirs = equal_area_directions(1000)[::20]
    with tempfile.TemporaryDirectory() as tmp:
        impl = {"old": _old_package(args.commit, Path(tmp)), "new": (AtmosphereParameters(), sky_radiance)}
        for atm, fn in impl.values():
            fn(atm, dirs[:2], WAVELENGTHS, sun_zenith=SUN_ZENITH, samples=8, scheduler="synchronous")  # compile
        print(f"load average {os.getloadavg()[0]:.1f} at start")
        rates: dict[str, list[float]] = {k: [] for k in impl}
        rad = {}
        for _ in range(args.runs):
            for name, (atm, fn) in impl.items():
                c0 = time.process_time()
                r = fn(atm, dirs, WAVELENGTHS, sun_zenith=SUN_ZENITH, samples=2048, scheduler="synchronous", seed=1)
                rates[name].append(dirs.shape[0] * r.samples / (time.process_time() - c0))
                rad[name] = r.radiance
    for name, v in rates.items():
        v.sort()
        print(f"{name} ({args.commit if name == 'old' else 'working tree'}): best {v[-1]:,.0f}, second {v[-2]:,.0f}, "
              f"median {np.median(v):,.0f} paths per CPU-second")
    print(f"new / old: best {rates['new'][-1] / rates['old'][-1]:.3f}, median "
          f"{np.median(rates['new']) / np.median(rates['old']):.3f}; radiances: largest relative difference "
          f"{np.max(np.abs(rad['new'] / rad['old'] - 1)):.1e}; load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
