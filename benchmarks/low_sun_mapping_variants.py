"""Sun-zenith mappings of the tables compared over a dense grid of suns against tables of 94 sun-zenith texels
(docs/accuracy.md, "A smooth twilight mapping").

The Monte Carlo cases of ``compare_low_sun_tables.py`` sit at seven suns, and whether a case is near a texel or
mid-cell depends on the mapping; this compares the lookups at every 0.1 deg of sun elevation from -8 to +3 deg (and
coarser by day) with the same lookups on tables of 94 sun-zenith texels (three times the default, the format-19
mapping: denser than any of the variants everywhere), for the three atmospheres of the low-sun reference, 48 view
directions from the ground (elevations 2-90 deg, azimuths 0-180 deg from the sun), 400 / 560 / 700 nm.

Two steps, one process per mapping (numba freezes the mapping's module constants when it compiles, so each variant
needs its own numba cache and table cache)::

    SKYSCATTER_CACHE_DIR=/tmp/m94 NUMBA_CACHE_DIR=/tmp/nb94 python benchmarks/low_sun_mapping_variants.py \\
        dump ref94.npz --mu-s 94
    SKYSCATTER_SUNMAP=0.64,0.453125,-9,1.5,1.5 SKYSCATTER_CACHE_DIR=/tmp/mD NUMBA_CACHE_DIR=/tmp/nbD \\
        python benchmarks/low_sun_mapping_variants.py dump D.npz
    python benchmarks/low_sun_mapping_variants.py compare ref94.npz main.npz D.npz

``SKYSCATTER_SUNMAP`` (read by ``skyscatter.precomputed.geometry`` at import, on the experiment's branch only):
``c,beta,lo,hi,w`` for ``x = (1 - c) x_19 + c ((1 - beta) g + beta x_a)``; unset: the format-19 mapping;
``SKYSCATTER_SUNMAP_DAY`` ``c2,lo2,hi2,w2`` adds ``c2 (g - h)``, ``h`` the CDF of a plateau in the day.
``compare`` prints, per atmosphere and band of sun elevations, median / 90th percentile / largest
``|x / x_94 - 1|`` [%] over suns, views and wavelengths.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from skyscatter.precomputed import cached_atmosphere

sys.path.insert(0, str(Path(__file__).resolve().parent))
from low_sun_montecarlo_reference import ATMOSPHERES  # noqa: E402  (sibling script)

SUNS = [round(float(v), 2) for v in np.arange(-8.0, 3.0001, 0.1)] + [4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0,
                                                                     12.0, 15.0, 20.0, 25.0, 30.0, 40.0, 50.0,
                                                                     60.0, 75.0, 90.0]
VIEW_ELEVATIONS = [2.0, 5.0, 10.0, 15.0, 30.0, 45.0, 60.0, 90.0]
VIEW_AZIMUTHS = [0.0, 20.0, 45.0, 90.0, 135.0, 180.0]
BANDS = [(-8.0, -4.5), (-4.5, -2.0), (-2.0, -0.5), (-0.5, 1.5), (1.5, 3.01), (4.0, 8.01), (9.0, 16.0), (19.0, 91.0)]
WAVELENGTHS = [400.0, 560.0, 700.0]


def directions() -> np.ndarray:
    """Unit view vectors (x east of the sun's azimuth, y towards it, z up), elevation-major."""
    out = []
    for e in VIEW_ELEVATIONS:
        for a in VIEW_AZIMUTHS:
            er, ar = math.radians(e), math.radians(a)
            out.append([math.cos(er) * math.sin(ar), math.cos(er) * math.cos(ar), math.sin(er)])
    return np.array(out)


def dump(path: str, n_mu_s: int | None) -> None:
    """Sky radiance [W m^-2 sr^-1 nm^-1] of the tables for every sun of ``SUNS``, (n_suns, n_views, 3) per
    atmosphere, written to ``path``."""
    sizes = {"scattering_mu_s": n_mu_s} if n_mu_s else None
    dirs = directions()
    out: dict[str, np.ndarray] = {"suns": np.array(SUNS)}
    for name, (_, make) in ATMOSPHERES.items():
        atm = cached_atmosphere(make(), wavelengths=WAVELENGTHS, sizes=sizes, progress=False)
        pos = np.array([0.0, 0.0, atm.parameters.bottom_radius])
        out[name] = np.stack([atm.sky_radiance(pos, dirs, np.array([0.0, math.cos(math.radians(s)),
                                                                    math.sin(math.radians(s))])) for s in SUNS])
    np.savez(path, **out)  # type: ignore[arg-type]
    print(f"wrote {path}")


def compare(reference: str, variants: list[str]) -> None:
    """Print the bands' median / 90th percentile / largest ``|x / x_ref - 1|`` [%] of each variant."""
    ref = np.load(reference)
    suns = ref["suns"]
    for name in ATMOSPHERES:
        print(f"## {name}: median / p90 / max |x / x_94 - 1| [%]")
        print("| tables | " + " | ".join(f"{a:g}..{b:g} deg" for a, b in BANDS) + " |")
        print("|---|" + "---|" * len(BANDS))
        for v in variants:
            rel = np.abs(np.load(v)[name] / ref[name] - 1.0) * 100.0
            cells = []
            for a, b in BANDS:
                x = rel[(suns >= a) & (suns < b)].ravel()
                cells.append(f"{np.median(x):.1f} / {np.percentile(x, 90):.1f} / {x.max():.0f}")
            print(f"| {Path(v).stem} | " + " | ".join(cells) + " |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    d = sub.add_parser("dump", help="the tables' radiance over the suns, to an .npz")
    d.add_argument("out")
    d.add_argument("--mu-s", type=int, default=None, help="sun-zenith texels (default: the tables' default)")
    c = sub.add_parser("compare", help="variants against the reference dump")
    c.add_argument("reference")
    c.add_argument("variants", nargs="+")
    args = ap.parse_args()
    if args.cmd == "dump":
        dump(args.out, args.mu_s)
    else:
        compare(args.reference, args.variants)


if __name__ == "__main__":
    main()
