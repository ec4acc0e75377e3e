"""The tables' read along the sun zenith between its texels, against tables with three times the texels
(docs/accuracy.md, "Low sun": "The read along the sun zenith").

The default tables have 32 sun-zenith texels; tables of 94 (``3 * 31 + 1``) hold every default texel (texel ``3 k``
of 94 is texel ``k`` of 32: the same mapping, :func:`skyscatter.precomputed.geometry.scattering_mu_s_coord`) and two
more in each default cell, at a third and two thirds of it. For each atmosphere the sky radiance from the ground
(the 15 views of ``benchmarks/low_sun_montecarlo_reference.py``: elevations 2, 5, 15 deg, azimuths 0-180 deg from
the sun) is computed at the suns of the 94-texel axis between -12 and +16 deg, from both tables. At a shared texel
the two tables differ by what the precomputation itself resolves; between the default texels the default tables'
lookup adds its read along the sun zenith. The rules compared between the default texels, from the default tables'
radiance at the default texels (the rendering lookups are linear in the table values along the sun zenith; their
weight along the azimuth is taken from the values interpolated along it, so the linear rule here is close to the
lookup but not equal to it: column ``lookup`` is the lookup itself):

* ``linear``: the lookups' rule;
* ``log-linear``: the geometric interpolation between the cell's two texels;
* ``log-quadratic``: the three-point Lagrange formula in the logarithm over the cell and the nearer neighbour
  ([Abramowitz1964] Eq. 25.2.11), kept between the cell's two values (:func:`skyscatter.precomputed.geometry.
  log_quadratic_weight`, the irradiance read's rule below the horizon).

Cells: median / 90th percentile / largest ``100 |x / x_94 - 1|`` [%] over views, wavelengths and the suns in each
band of sun elevation.

``python benchmarks/low_sun_mu_s_read.py [--atmospheres earth,turbidity3,aod05] [--wavelengths 400,560,700]``
(about 1 + 3 table computations per atmosphere at the compared wavelengths).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from skyscatter.precomputed import cached_atmosphere
from skyscatter.precomputed.kernels import mu_s_texels

sys.path.insert(0, str(Path(__file__).resolve().parent))
from low_sun_montecarlo_reference import ATMOSPHERES, directions  # noqa: E402  (sibling script)

BANDS = [(-12.0, -7.0), (-7.0, -4.5), (-4.5, -2.0), (-2.0, -0.5), (-0.5, 1.5), (1.5, 4.0), (4.0, 8.0), (8.0, 16.5)]


def radiance_at_suns(atm, elevations: np.ndarray) -> np.ndarray:
    """Sky radiance (n_suns, n_views, n_wavelengths) from the ground at the sun elevations [deg]."""
    pos = np.array([0.0, 0.0, atm.parameters.bottom_radius])
    out = []
    for e in elevations:
        s = math.radians(float(e))
        out.append(atm.sky_radiance(pos, directions(), np.array([0.0, math.cos(s), math.sin(s)])))
    return np.array(out)


def rules(v: np.ndarray) -> dict[str, np.ndarray]:
    """The rules of the module docstring at every index of the fine axis ``v`` (n_fine, ...), from its values at
    the indices ``3 k`` (the default texels); the texels keep their values."""
    n = v.shape[0]
    out = {k: v.copy() for k in ("linear", "log-linear", "log-quadratic")}
    for i in range(n):
        j = (i // 3) * 3
        if i % 3 == 0 or j + 3 >= n:
            continue
        w = (i - j) / 3.0
        a, b = v[j], v[j + 3]
        lin = (1.0 - w) * a + w * b
        out["linear"][i] = lin
        with np.errstate(all="ignore"):
            geo = np.where((a > 0) & (b > 0), a ** (1.0 - w) * b ** w, lin)
        out["log-linear"][i] = geo
        # the cell and its nearer neighbour (geometry.irradiance_log_nodes), t relative to the middle texel
        j0 = j - 3 if w < 0.5 else j
        j0 = min(max(j0, 0), n - 1 - 6 - (n - 1) % 3)
        t = (i - (j0 + 3)) / 3.0
        y0, y1, y2 = v[j0], v[j0 + 3], v[j0 + 6]
        ok = (y0 > 0) & (y1 > 0) & (y2 > 0)
        with np.errstate(all="ignore"):
            q = np.exp(0.5 * t * (t - 1.0) * np.log(y0) + (1.0 - t * t) * np.log(y1)
                       + 0.5 * t * (t + 1.0) * np.log(y2))
        out["log-quadratic"][i] = np.where(ok, np.clip(q, np.minimum(a, b), np.maximum(a, b)), geo)
    return out


def spread(x: np.ndarray, ref: np.ndarray, sel: list[int]) -> str:
    """``median / 90th percentile / largest`` of ``100 |x / ref - 1|`` [%] at the fine-axis indices ``sel``."""
    if not sel:
        return "-"
    e = np.abs(x[sel] / ref[sel] - 1.0) * 100.0
    e = e[np.isfinite(e)]
    return f"{np.median(e):.1f} / {np.percentile(e, 90):.1f} / {e.max():.1f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--atmospheres", default=",".join(ATMOSPHERES))
    ap.add_argument("--wavelengths", default="400,560,700")
    args = ap.parse_args()
    wl = [float(w) for w in args.wavelengths.split(",")]
    for name in args.atmospheres.split(","):
        params = ATMOSPHERES[name][1]()
        fine = cached_atmosphere(params, wavelengths=wl, sizes={"scattering_mu_s": 94}, progress=False)
        default = cached_atmosphere(params, wavelengths=wl, progress=False)
        p = fine.parameters
        el = np.degrees(np.arcsin(mu_s_texels(p.bottom_radius, p.top_radius, p.mu_s_min, 94)))
        el = el[el <= 16.5]
        ref = radiance_at_suns(fine, el)
        got = radiance_at_suns(default, el)
        tex = radiance_at_suns(default, el[::3])
        v = np.zeros_like(got)
        v[::3] = tex
        cand = {"lookup": got, **rules(v)}
        print(f"## {name}, {wl} nm: median / 90 % / largest |x / x_94 - 1| [%]")
        print("| sun [deg] | at the default texels | " + " | ".join(f"between: {k}" for k in cand) + " |")
        print("|---|---|" + "---|" * len(cand))
        for lo, hi in BANDS:
            between = [i for i in range(len(el)) if i % 3 and lo <= el[i] < hi and (i // 3) * 3 + 3 < len(el)]
            at = [i for i in range(0, len(el), 3) if lo <= el[i] < hi]
            print(f"| {lo:+g}..{hi:+g} | {spread(got, ref, at)} | "
                  + " | ".join(spread(x, ref, between) for x in cand.values()) + " |", flush=True)


if __name__ == "__main__":
    main()
