"""The precomputed tables against the stored low-sun Monte Carlo values (tests/data/low_sun_montecarlo.json, made
by benchmarks/low_sun_montecarlo_reference.py): docs/accuracy.md "Low sun".

For each atmosphere and sun elevation, the relative difference ``tables / MC - 1`` per view direction (elevation
2, 5, 15 deg; azimuth 0-180 deg from the sun) at the worst of the compared wavelengths, and whether it is within
the target: 5 % or 2 Monte Carlo standard errors, whichever is larger.

``python benchmarks/compare_low_sun_tables.py [--wavelengths 400,560,700] [--sizes scattering_mu_s=64,...]``
(tables computed at the compared wavelengths only: radiance at a table wavelength does not depend on the others;
``--wavelengths all`` takes the 16 stored ones).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from skyscatter.precomputed import cached_atmosphere

sys.path.insert(0, str(Path(__file__).resolve().parent))
from low_sun_montecarlo_reference import ATMOSPHERES, directions  # noqa: E402  (the sibling script)

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "low_sun_montecarlo.json"


def reference() -> dict:
    return json.loads(DATA.read_text())


def case_errors(atm, case: dict, columns: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """(relative difference, relative MC standard error), (n_views, n_columns), for one stored case."""
    s = np.radians(case["sun_elevation_deg"])
    sun = np.array([0.0, np.cos(s), np.sin(s)])
    pos = np.array([0.0, 0.0, atm.parameters.bottom_radius])
    tab = atm.sky_radiance(pos, directions(), sun)
    mc = np.array(case["radiance"])[:, columns]
    se = np.array(case["radiance_stderr"])[:, columns]
    return tab / mc - 1.0, se / mc


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--wavelengths", default="400,560,700", help="compared wavelengths [nm] or 'all'")
    ap.add_argument("--sizes", default="", help="table size overrides, e.g. scattering_mu_s=64")
    ap.add_argument("--atmospheres", default=",".join(ATMOSPHERES))
    args = ap.parse_args()
    doc = reference()
    stored = doc["wavelengths_nm"]
    wl = stored if args.wavelengths == "all" else [float(w) for w in args.wavelengths.split(",")]
    columns = [stored.index(w) for w in wl]
    sizes = {k: int(v) for k, v in (kv.split("=") for kv in args.sizes.split(",") if kv)} or None
    views = doc["views_deg"]
    print(f"# wavelengths {wl}; sizes {sizes}; cells: worst wavelength's 100 (tables / MC - 1) ± MC stderr [%]; "
          "* outside the target (5 % or 2 stderr)")
    print("| atmosphere | sun [deg] | " + " | ".join(f"{e:g}/{a:g}" for e, a in views) + " | outside |")
    print("|---|---|" + "---|" * len(views) + "---|")
    for name in args.atmospheres.split(","):
        t0 = time.perf_counter()
        atm = cached_atmosphere(ATMOSPHERES[name][1](), wavelengths=wl, sizes=sizes, progress=False)
        t_tab = time.perf_counter() - t0
        for case in doc["cases"]:
            if case["atmosphere"] != name:
                continue
            rel, rse = case_errors(atm, case, columns)
            worst = np.argmax(np.abs(rel), axis=1)
            r = rel[np.arange(len(views)), worst]
            e = rse[np.arange(len(views)), worst]
            bad = np.abs(rel) > np.maximum(0.05, 2.0 * rse)
            cells = [f"{100 * a:+.1f}±{100 * b:.1f}{'*' if bad[i].any() else ''}" for i, (a, b) in
                     enumerate(zip(r, e, strict=True))]
            print(f"| {name} | {case['sun_elevation_deg']:+g} | " + " | ".join(cells)
                  + f" | {int(bad.any(axis=1).sum())}/{len(views)} |", flush=True)
        print(f"# {name}: tables {t_tab:.0f} s", flush=True)


if __name__ == "__main__":
    main()
