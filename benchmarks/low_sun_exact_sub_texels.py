"""How many low-sun directions would stay outside the target if the refined sun-zenith read's sub-texels were
exact: an emulation from tables of 94 sun-zenith texels (docs/accuracy.md, "Low sun", "The refined sun-zenith
read"; nothing in src/ changed).

The lookups read the three 4D scattering tables on a sun-zenith axis refined in twilight
(``lookup.refine_sun_zenith``: the stored cells of the default 32 texels below and across the horizon, 8 since
2026-12-05 and 7 before, split into 3 sub-cells whose texels hold a four-point Lagrange rule in the logarithm, with
fall-backs at the Earth's shadow). Since 2026-12-05 the library computes the single scattering's sub-texels at their
suns (``compute.stored_single_scattering``): variant (b) below is then the library's own (a), to the 94-texel
tables' half-precision rounding; before, (a) was the rule for all three tables (64 of 315 with 7 cells and 6 orders).
The sub-texels sit exactly at texels of tables with 94 sun-zenith texels (texel ``3k`` of 94 is texel ``k`` of
32; the sub-texels of cell ``k`` are 94-texel texels ``3k + 1``, ``3k + 2``; refined index ``j < 3 cells`` equals
94-texel index ``j``). Variants, each evaluated with the general per-ray kernel (``sky_radiance`` with one
position per ray) on the refined tables put in the 32-texel atmosphere's ``_lookup_tables_cache``:

* ``a``: the library's own refined tables (``PrecomputedAtmosphere.lookup_tables``), as is;
* ``b``: (a) with the single-scattering tables' sub-texels (single Rayleigh and single Mie, refined columns
  ``j < 3 cells`` with ``j % 3 != 0``) replaced by the 94-texel tables' columns ``j`` (computed by the
  precomputation at those sun zeniths); the multiple scattering's sub-texels keep the Lagrange rule;
* ``c``: (b) with the multiple scattering's sub-texels from the 94-texel tables too (the ceiling of the approach);
* ``d``: (c) with the multiple scattering's stored texels of the split cells (refined columns ``j <= 3 cells``)
  from the 94-texel tables too: unlike the single scattering's, the two precomputations' multiple scattering
  differs at the shared sun zeniths (its orders interpolate the scattering density along the sun zenith, so the
  texel spacing enters them; the ``stored texels`` line printed), so (c) mixes the two there;
* ``e``: (b) with the multiple scattering's sub-texels of the library's rule times the rule's own error on the
  94-texel tables (their sub-texels over the rule applied to their every third texel): exact sub-texels of the
  32-texel precomputation's multiple scattering as far as the rule's error is the same in both, without (c)'s mix.

The stored texels (``j % 3 == 0`` and everything above the split) are the 32-texel tables' in every variant but
(d), so suns above the split cells read the same values in (a), (b), (c) and (e); (d) changes the cell across the
horizon too (its lower texel, refined ``j = 3 cells``, -0.43 deg). Each is counted against the stored low-sun Monte
Carlo (tests/data/low_sun_montecarlo.json) with the rule of tests/test_precomputed_low_sun.py (``_errors``: a
direction is outside when ``|tables / MC - 1|`` exceeds 5 % or 2 MC standard errors, whichever is larger, at any
of 400, 560, 700 nm). Also printed: the observer path's count (``compare_low_sun_tables.py``'s, one position) and
the largest relative difference between it and variant ``a`` (the per-ray path reads the same refined values), the
94-texel tables' stored-texel columns ``3k`` against the 32-texel tables' texels ``k`` (two precomputations, so
not zero), and, for the cases of ``--detail`` (default Earth at -5.1 deg), the 15 views' worst-wavelength
relative errors in each variant.

``PYTHONPATH=src python benchmarks/low_sun_exact_sub_texels.py [--atmospheres earth,turbidity3,aod05]
[--detail earth:-5.1,aod05:-2.3]`` (the default and the 94-texel tables at the three wavelengths come from the
table cache; computed if missing, which takes tens of minutes; with them cached the run takes a few CPU-seconds).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from skyscatter.precomputed import cached_atmosphere, lookup
from skyscatter.precomputed.geometry import MU_S_SPLIT

sys.path.insert(0, str(Path(__file__).resolve().parent))
from low_sun_montecarlo_reference import ATMOSPHERES  # noqa: E402  (sibling script)

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "low_sun_montecarlo.json"
WAVELENGTHS = [400.0, 560.0, 700.0]
SINGLE = ("single_rayleigh", "single_mie")
SCATTERING = SINGLE + ("multiple",)


def view_directions(views: list[list[float]]) -> np.ndarray:
    """Unit view directions, sun azimuth 0 (tests/test_precomputed_low_sun.py ``_directions``)."""
    out = []
    for e, a in views:
        er, ar = math.radians(e), math.radians(a)
        out.append([math.cos(er) * math.sin(ar), math.cos(er) * math.cos(ar), math.sin(er)])
    return np.array(out)


def errors(tab: np.ndarray, case: dict, cols: list[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(tables / MC - 1, MC relative standard error, outside the target), (n_views, 3)."""
    mc = np.array(case["radiance"])[:, cols]
    se = np.array(case["radiance_stderr"])[:, cols]
    rel, rse = tab / mc - 1.0, se / mc
    return rel, rse, np.abs(rel) > np.maximum(0.05, 2.0 * rse)


def decoded(table) -> np.ndarray:
    """A stored 4D table as float32 (a :class:`.storage.HalfTable` decoded)."""
    return np.asarray(table[:] if not isinstance(table, np.ndarray) else table, dtype=np.float32)


def variants(atm32, atm94) -> dict[str, dict]:
    """The refined tables of the three variants (module docstring), as dicts for ``_lookup_tables_cache``."""
    cells = atm32._mu_s_cells
    split = MU_S_SPLIT * cells
    own = atm32.lookup_tables  # the library's refined tables (built here on first use)
    sub = [j for j in range(split) if j % MU_S_SPLIT != 0]
    out = {"a": dict(own)}
    b = dict(own)
    for name in SINGLE:
        t = own[name].copy()
        t[:, :, sub] = decoded(atm94.stored[name])[:, :, sub]
        b[name] = t
    out["b"] = b
    c = dict(b)
    t = own["multiple"].copy()
    t[:, :, sub] = decoded(atm94.stored["multiple"])[:, :, sub]
    c["multiple"] = t
    out["c"] = c
    d = dict(c)
    t = c["multiple"].copy()
    t[:, :, :split + 1] = decoded(atm94.stored["multiple"])[:, :, :split + 1]
    d["multiple"] = t
    out["d"] = d
    m94 = decoded(atm94.stored["multiple"])
    rule94 = lookup.refine_sun_zenith(np.ascontiguousarray(m94[:, :, ::MU_S_SPLIT]), cells)
    e = dict(b)
    t = own["multiple"].copy()
    for j in sub:
        ok = (rule94[:, :, j] > 0.0) & (m94[:, :, j] > 0.0)
        t[:, :, j] = np.where(ok, t[:, :, j] * m94[:, :, j] / np.where(ok, rule94[:, :, j], 1.0), t[:, :, j])
    e["multiple"] = t
    out["e"] = e
    return out


def texel_check(atm32, atm94) -> str:
    """Median and largest |94-texel column 3k / 32-texel column k - 1| over the split cells' stored texels, where
    both are above 1e-3 of the column's maximum (the two precomputations' own difference at shared sun zeniths)."""
    cells = atm32._mu_s_cells
    parts = []
    for name in SCATTERING:
        t32 = decoded(atm32.stored[name])[:, :, :cells + 1]
        t94 = decoded(atm94.stored[name])[:, :, 0:MU_S_SPLIT * cells + 1:MU_S_SPLIT]
        ok = (t32 > 1e-3 * t32.max()) & (t94 > 0)
        d = np.abs(t94[ok] / t32[ok] - 1.0)
        parts.append(f"{name} median {100 * np.median(d):.2f} % max {100 * d.max():.1f} %")
    return "; ".join(parts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--atmospheres", default=",".join(ATMOSPHERES))
    ap.add_argument("--detail", default="earth:-5.1",
                    help="comma-separated atmosphere:sun elevation [deg] cases whose views are printed")
    args = ap.parse_args()
    doc = json.loads(DATA.read_text())
    cols = [doc["wavelengths_nm"].index(w) for w in WAVELENGTHS]
    views = doc["views_deg"]
    dirs = view_directions(views)
    wanted = {(n, float(e)) for n, e in (c.split(":") for c in args.detail.split(",") if c)}
    print("| atmosphere | sun [deg] | observer path | a: library | b: exact single sub-texels "
          "| c: all exact sub-texels | d: c + 94-texel multiple in the split "
          "| e: b + multiple's rule error removed | max |observer / a - 1| |")
    print("|---|---|---|---|---|---|---|---|---|")
    totals = dict.fromkeys(("obs", "a", "b", "c", "d", "e"), 0)
    details: dict[tuple[str, float], dict] = {}
    for name in args.atmospheres.split(","):
        params = ATMOSPHERES[name][1]()
        atm32 = cached_atmosphere(params, wavelengths=WAVELENGTHS, progress=False)
        atm94 = cached_atmosphere(params, wavelengths=WAVELENGTHS, sizes={"scattering_mu_s": 94}, progress=False)
        print(f"# {name}: cells {atm32._mu_s_cells}; stored texels 94 vs 32: {texel_check(atm32, atm94)}",
              flush=True)
        tabs = variants(atm32, atm94)
        pos = np.array([0.0, 0.0, atm32.parameters.bottom_radius])
        pos_rays = np.ascontiguousarray(np.broadcast_to(pos, dirs.shape))
        for case in doc["cases"]:
            if case["atmosphere"] != name:
                continue
            sun_elev = case["sun_elevation_deg"]
            s = math.radians(sun_elev)
            sun = np.array([0.0, math.cos(s), math.sin(s)])
            atm32._lookup_tables_cache = tabs["a"]
            obs = atm32.sky_radiance(pos, dirs, sun)  # the observer path (compare_low_sun_tables.py)
            counts = {"obs": int(errors(obs, case, cols)[2].any(axis=1).sum())}
            res = {}
            for v in ("a", "b", "c", "d", "e"):
                atm32._lookup_tables_cache = tabs[v]
                tab = atm32.sky_radiance(pos_rays, dirs, sun)  # one position per ray: the general kernel
                rel, rse, bad = errors(tab, case, cols)
                counts[v] = int(bad.any(axis=1).sum())
                res[v] = (tab, rel, rse, bad)
            for k, n in counts.items():
                totals[k] += n
            diff = float(np.max(np.abs(obs / res["a"][0] - 1.0)))
            print(f"| {name} | {sun_elev:+g} | {counts['obs']} | {counts['a']} | {counts['b']} | {counts['c']} "
                  f"| {counts['d']} | {counts['e']} | {diff:.1e} |", flush=True)
            if (name, float(sun_elev)) in wanted:
                details[name, float(sun_elev)] = res
        atm32._lookup_tables_cache = tabs["a"]
    print("| all | | " + " | ".join(str(n) for n in totals.values()) + " | |")
    for (name, sun_elev), res in details.items():
        print(f"\n# {name} at {sun_elev:+g} deg: worst wavelength's 100 (tables / MC - 1) ± MC stderr [%] per view; "
              "* outside")
        print("| view elev/az [deg] | " + " | ".join(res) + " |")
        print("|---|" + "---|" * len(res))
        for i, (e, a) in enumerate(views):
            cells = []
            for rel, rse, bad in (r[1:] for r in res.values()):
                k = int(np.argmax(np.abs(rel[i])))
                cells.append(f"{100 * rel[i, k]:+.1f}±{100 * rse[i, k]:.1f}{'*' if bad[i].any() else ''}")
            print(f"| {e:g}/{a:g} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
