"""Reads along the sun zenith in twilight against the stored Monte Carlo (docs/accuracy.md, "Low sun": "The read
along the sun zenith in twilight").

For every stored case of tests/data/low_sun_montecarlo.json with the sun below the horizon (made by
``benchmarks/low_sun_montecarlo_reference.py``; the suns -2.3 and -5.1 deg sit in the middle of a cell of the default
tables' sun-zenith texels, -3 and -6 deg within 0.12 deg of a texel), the sky from the ground read between the two
sun-zenith texels around the sun by four rules, from the default tables' radiance at the texel suns (the lookups
exactly at a texel, 400/560/700 nm):

* ``linear``: the lookups themselves at the case's sun (their rule);
* ``geometric``: ``a^(1 - w) b^w`` of the radiance ``a``, ``b`` at the cell's two texels, ``w`` the sun's fraction of
  the cell ([Abramowitz1964] Eq. 25.2.1 in the logarithm; exact for a radiance exponential in the texture
  coordinate);
* ``power 1/2``: ``((1 - w) a^(1/2) + w b^(1/2))^2`` (between the two: non-decreasing in ``a`` and ``b`` like them);
* ``log-quadratic``: the three-point Lagrange formula in the logarithm over the cell and its nearer neighbour
  ([Abramowitz1964] Eq. 25.2.11), kept between ``a`` and ``b`` (its weight on the third texel is negative).

The rules other than ``linear`` are emulated from the texel values (the lookups' azimuth weights are taken at each
texel, not from the values read along the sun zenith, so they differ from a lookup built on them by up to a few per
cent). Per case: how many of the 15 directions miss the issue's target (5 % or 2 Monte Carlo standard errors,
whichever is larger, at some wavelength) and the median of ``tables / MC - 1``. ``--sizes scattering_mu_s=94`` reads
the lookups of tables with more sun-zenith texels instead (``linear`` only is then meaningful).

``python benchmarks/low_sun_twilight_reads.py [--sizes scattering_mu_s=94]`` (tables from the cache or computed at
the three wavelengths: about a minute each).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from skyscatter.precomputed import cached_atmosphere
from skyscatter.precomputed.geometry import scattering_mu_s_coord
from skyscatter.precomputed.kernels import mu_s_texels

sys.path.insert(0, str(Path(__file__).resolve().parent))
from low_sun_montecarlo_reference import ATMOSPHERES  # noqa: E402  (sibling scripts)
from low_sun_mu_s_read import radiance_at_suns  # noqa: E402

DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "low_sun_montecarlo.json"
WAVELENGTHS = [400.0, 560.0, 700.0]


def reads(atm, sun_elev: float) -> dict[str, np.ndarray]:
    """The four rules of the module docstring at the sun elevation [deg]: radiance (n_views, n_wavelengths)."""
    p = atm.parameters
    n_s = atm.sizes.scattering_mu_s
    texels = np.degrees(np.arcsin(mu_s_texels(p.bottom_radius, p.top_radius, p.mu_s_min, n_s)))
    pc = scattering_mu_s_coord(math.sin(math.radians(sun_elev)), p.bottom_radius, p.top_radius, p.mu_s_min, n_s)
    i = min(int(math.floor(pc)), n_s - 2)
    w = pc - i
    j0 = min(max(i - 1 if w < 0.5 else i, 0), n_s - 3)
    at = radiance_at_suns(atm, texels[j0:j0 + 3])
    a, b = at[i - j0], at[i + 1 - j0]
    t = pc - (j0 + 1)
    with np.errstate(all="ignore"):
        quad = np.exp(0.5 * t * (t - 1.0) * np.log(at[0]) + (1.0 - t * t) * np.log(at[1])
                      + 0.5 * t * (t + 1.0) * np.log(at[2]))
    return {"linear": radiance_at_suns(atm, [sun_elev])[0],
            "geometric": a ** (1.0 - w) * b ** w,
            "power 1/2": ((1.0 - w) * np.sqrt(a) + w * np.sqrt(b)) ** 2,
            "log-quadratic": np.clip(quad, np.minimum(a, b), np.maximum(a, b))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="", help="table size overrides, e.g. scattering_mu_s=94")
    args = ap.parse_args()
    sizes = {k: int(v) for k, v in (kv.split("=") for kv in args.sizes.split(",") if kv)} or None
    doc = json.loads(DATA.read_text())
    cols = [doc["wavelengths_nm"].index(w) for w in WAVELENGTHS]
    cases = sorted((c for c in doc["cases"] if c["sun_elevation_deg"] < 0.0),
                   key=lambda c: (list(ATMOSPHERES).index(c["atmosphere"]), -c["sun_elevation_deg"]))
    totals: dict[str, int] = {}
    print(f"# sizes {sizes}; cells: directions outside of 15 / median 100 (tables / MC - 1) [%]")
    print("| atmosphere | sun [deg] | paths | linear | geometric | power 1/2 | log-quadratic |")
    print("|---|---|---|---|---|---|---|")
    for c in cases:
        atm = cached_atmosphere(ATMOSPHERES[c["atmosphere"]][1](), wavelengths=WAVELENGTHS, sizes=sizes,
                                progress=False)
        mc = np.array(c["radiance"])[:, cols]
        limit = np.maximum(0.05, 2.0 * np.array(c["radiance_stderr"])[:, cols] / mc)
        cells = []
        for rule, value in reads(atm, c["sun_elevation_deg"]).items():
            rel = value / mc - 1.0
            outside = int((np.abs(rel) > limit).any(axis=1).sum())
            totals[rule] = totals.get(rule, 0) + outside
            cells.append(f"{outside} / {100 * np.median(rel):+.1f}")
        print(f"| {c['atmosphere']} | {c['sun_elevation_deg']:+g} | {c['paths']} | " + " | ".join(cells) + " |",
              flush=True)
    print("| all | | | " + " | ".join(str(v) for v in totals.values()) + " |")


if __name__ == "__main__":
    main()
