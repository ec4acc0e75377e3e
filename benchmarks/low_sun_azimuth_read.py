"""How much of the low-sun miss is the read along the view-sun azimuth: an emulation on tables of 15 azimuth texels,
whose every other texel is a texel of the default 8 (docs/accuracy.md, "Low sun", "Known limits"). Measured only:
nothing here is in the library.

The lookups' tables (``PrecomputedAtmosphere.lookup_tables``: the stored tables refined along the sun zenith) of a
15-texel precomputation are read by the library's general per-ray kernel (one position per ray) with their odd
azimuth texels replaced, against the stored low-sun Monte Carlo (tests/data/low_sun_montecarlo.json; target 5 % or 2
standard errors, whichever is larger, at 400 / 560 / 700 nm):

* on the 15-texel precomputation (``--base 15``): ``orig`` as computed; ``lin`` the multiple scattering's odd texels
  the lookups' log-linear read of their two neighbours at the cell's middle (:func:`.sampling.nu_weight`'s rule: the
  middle wavelength's weight for every wavelength), the single scattering as computed; ``cubic`` those texels by the
  four-point rule ``(-a + 9 b + 9 c - d) / 16`` of the stored ratio to the lobe (mirrored at 0 and 180 deg, where
  the azimuth axis is symmetric), clipped at zero;
* on the default 8-texel precomputation (``--base 8``): the multiple scattering's texels the 8-texel tables' own,
  its odd texels by the same two rules (``lin``, ``cubic``), the single scattering's every texel the 15-texel
  precomputation's (exact: a single-scattering texel does not depend on the axis' resolution), beside the library
  as it is (``8``). This is a refined azimuth axis as data for the lookups, the single scattering computed at the
  sub-texels and the multiple by a rule, emulated.

``python benchmarks/low_sun_azimuth_read.py [--base 8|15]`` (tables at the three wavelengths, cached; about two
minutes the first time).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from skyscatter.precomputed import cached_atmosphere

sys.path.insert(0, str(Path(__file__).resolve().parent))
from low_sun_exact_sub_texels import DATA, errors, view_directions  # noqa: E402  (sibling scripts)
from low_sun_montecarlo_reference import ATMOSPHERES  # noqa: E402

WAVELENGTHS = [400.0, 560.0, 700.0]
MIDDLE = 1  # the middle wavelength's column, whose weight the lookups apply to every wavelength


def middle_log_linear(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The lookups' read half way between two texels (:func:`.geometry.log_lerp_weight` at ``w`` = 1/2 from the
    middle wavelength's values, applied to every wavelength: ``w' = 1 / (1 + sqrt(b / a))``)."""
    am, bm = a[..., MIDDLE:MIDDLE + 1], b[..., MIDDLE:MIDDLE + 1]
    d = am + np.sqrt(am * bm)
    w = np.divide(am, d, out=np.full_like(d, 0.5), where=d > 0.0)
    return a + w * (b - a)


def fill_odd(even: np.ndarray, rule: str) -> np.ndarray:
    """A table of ``2 k - 1`` azimuth texels (axis 3) from ``k`` (its even texels), the odd ones by ``rule``."""
    k = even.shape[3]
    out = np.empty((*even.shape[:3], 2 * k - 1, *even.shape[4:]), dtype=even.dtype)
    out[:, :, :, 0::2] = even
    for j in range(k - 1):
        a, b = even[:, :, :, j], even[:, :, :, j + 1]
        if rule == "lin":
            out[:, :, :, 2 * j + 1] = middle_log_linear(a, b)
        else:
            before = even[:, :, :, 1 if j == 0 else j - 1]  # the axis is symmetric about 0 and 180 deg
            after = even[:, :, :, k - 2 if j + 2 >= k else j + 2]
            out[:, :, :, 2 * j + 1] = np.maximum((-before + 9.0 * a + 9.0 * b - after) / 16.0, 0.0)
    return np.ascontiguousarray(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", choices=("8", "15"), default="8",
                    help="the precomputation the multiple scattering is from")
    ap.add_argument("--atmospheres", default=",".join(ATMOSPHERES))
    args = ap.parse_args()
    doc = json.loads(DATA.read_text())
    cols = [doc["wavelengths_nm"].index(w) for w in WAVELENGTHS]
    dirs = view_directions(doc["views_deg"])
    names = ("8", "lin", "cubic") if args.base == "8" else ("orig", "lin", "cubic")
    totals = dict.fromkeys(names, 0)
    print("| atmosphere | sun [deg] | " + " | ".join(names) + " |   (directions outside; the worst cell [%])")
    print("|---|---|" + "---|" * len(names))
    for name in args.atmospheres.split(","):
        params = ATMOSPHERES[name][1]()
        atm15 = cached_atmosphere(params, wavelengths=WAVELENGTHS, sizes={"scattering_nu": 15}, progress=False)
        own = dict(atm15.lookup_tables)
        if args.base == "8":
            atm8 = cached_atmosphere(params, wavelengths=WAVELENGTHS, progress=False)
            multiple = np.asarray(atm8.lookup_tables["multiple"])
            variants = {"8": (atm8, None)}
        else:
            multiple = np.ascontiguousarray(np.asarray(own["multiple"])[:, :, :, 0::2])
            variants = {"orig": (atm15, own)}
        for rule in ("lin", "cubic"):
            variants[rule] = (atm15, {**own, "multiple": fill_odd(multiple, rule)})
        pos = np.array([0.0, 0.0, params.bottom_radius])
        rays = np.ascontiguousarray(np.broadcast_to(pos, dirs.shape))
        for case in doc["cases"]:
            if case["atmosphere"] != name:
                continue
            s = math.radians(case["sun_elevation_deg"])
            sun = np.array([0.0, math.cos(s), math.sin(s)])
            cells = []
            for v, (atm, tables) in variants.items():
                if tables is not None:
                    atm._lookup_tables_cache = tables
                rel, rse, bad = errors(atm.sky_radiance(rays, dirs, sun), case, cols)
                n = int(bad.any(axis=1).sum())
                totals[v] += n
                i = np.unravel_index(np.argmax(np.abs(rel) / np.maximum(0.05, 2.0 * rse)), rel.shape)
                cells.append(f"{n} ({100 * rel[i]:+.1f})")
            print(f"| {name} | {case['sun_elevation_deg']:+g} | " + " | ".join(cells) + " |", flush=True)
        atm15._lookup_tables_cache = own
    print("| all | | " + " | ".join(str(n) for n in totals.values()) + " |")


if __name__ == "__main__":
    main()
