"""The precomputed tables against the stored low-sun Monte Carlo values (tests/data/low_sun_montecarlo.json, made
by benchmarks/low_sun_montecarlo_reference.py): docs/accuracy.md "Low sun".

For each atmosphere and sun elevation, the relative difference ``tables / MC - 1`` per view direction (elevation
2, 5, 15 deg; azimuth 0-180 deg from the sun) at the worst of the compared wavelengths, and whether it is within
the target: 5 % or 2 Monte Carlo standard errors, whichever is larger.

``python benchmarks/compare_low_sun_tables.py [--wavelengths 400,560,700] [--sizes scattering_mu_s=64,...]``
(tables computed at the compared wavelengths only: radiance at a table wavelength does not depend on the others;
``--wavelengths all`` takes the 16 stored ones).

``--split`` adds, per case, the tables' single and multiple scattering apart at the cell's worst wavelength: the
single scattering against the independent integral of ``tests/precomputed_reference.py`` (point sun, its own
optical depths) and the multiple scattering against the Monte Carlo minus that integral, with the single
scattering's share of the Monte Carlo radiance (cells ``single % / multiple % ± stderr % / share %``).
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
from diagnose_low_sun import reference_module, split  # noqa: E402  (sibling scripts)
from low_sun_montecarlo_reference import ATMOSPHERES, directions  # noqa: E402

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


def split_cells(atm, case: dict, columns: list[int], worst: np.ndarray, wl: list[float]) -> list[str]:
    """Per view: ``single % / multiple % ± stderr % / single share %`` at the view's worst wavelength (module
    docstring)."""
    ref = reference_module()
    p = atm.parameters
    s = np.radians(case["sun_elevation_deg"])
    sun = np.array([0.0, np.cos(s), np.sin(s)])
    pos = np.array([0.0, 0.0, p.bottom_radius])
    dirs = directions()
    single, mult = split(atm)
    tab_s = single.sky_radiance(pos, dirs, sun)
    tab_m = mult.sky_radiance(pos, dirs, sun)
    mc = np.array(case["radiance"])[:, columns]
    se = np.array(case["radiance_stderr"])[:, columns]
    out = []
    for i, d in enumerate(dirs):
        k = int(worst[i])
        ref_s = float(ref.single_scattering(p.bottom_radius, float(d[2]), float(sun[2]), float(d @ sun), p,
                                            np.array([wl[k]]))[0])
        m_ref = mc[i, k] - ref_s
        s_err = f"{100 * (tab_s[i, k] / ref_s - 1):+.0f}" if ref_s > 1e-3 * mc[i, k] else "-"
        out.append(f"{s_err}/{100 * (tab_m[i, k] / m_ref - 1):+.1f}±{100 * se[i, k] / m_ref:.1f}"
                   f"/{100 * ref_s / mc[i, k]:.0f}")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--wavelengths", default="400,560,700", help="compared wavelengths [nm] or 'all'")
    ap.add_argument("--sizes", default="", help="table size overrides, e.g. scattering_mu_s=64")
    ap.add_argument("--atmospheres", default=",".join(ATMOSPHERES))
    ap.add_argument("--split", action="store_true", help="also single and multiple scattering apart")
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
            if args.split:
                print(f"| {name} | {case['sun_elevation_deg']:+g} split | "
                      + " | ".join(split_cells(atm, case, columns, worst, wl)) + " | |", flush=True)
        print(f"# {name}: tables {t_tab:.0f} s", flush=True)


if __name__ == "__main__":
    main()
