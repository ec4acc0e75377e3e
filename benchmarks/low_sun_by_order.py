"""The tables against the Monte Carlo order by order at low sun (docs/accuracy.md, "Low sun", "Order by order").

For one atmosphere and sun elevation, the Monte Carlo reference's orders of scattering apart
(:func:`skyscatter.montecarlo.sky_radiance` with ``orders=1``, ``2`` and ``(3, None)``: the same paths, the three
add up to the whole; docs/montecarlo.md, "Orders of scattering") at the 15 view directions of
``benchmarks/low_sun_montecarlo_reference.py`` (elevation 2, 5, 15 deg; azimuth 0-180 deg from the sun), and the
tables' orders: ``orders=1`` (single scattering), ``orders=2`` minus that (the second order) and the default eight
orders with their tail minus ``orders=2`` (the third and later). Per view and wavelength ``100 (tables / MC - 1)``
with the difference in Monte Carlo standard errors in brackets, each order's share of the Monte Carlo radiance,
and per order the mean and median over the views.

``python benchmarks/low_sun_by_order.py --atm earth --sun=-3 [--paths 2097152] [--wavelengths 400,560,700]
[--seed 7] [--sizes scattering_nu=15,...] [--mc-cache DIR]``

``--atm`` also takes ``rayleigh`` (no aerosol, no ozone) and ``noozone`` (the Earth defaults without ozone).
``--mc-cache DIR`` keeps each Monte Carlo case in ``DIR`` (``.npz``, keyed by atmosphere, sun, paths, seed and
wavelengths) and reads it back, so that table sizes can be compared against one run. Measured 2026-12-06 (2097152
paths per window, seed 7; 40-130 s per window on the shared 2 cores): docs/accuracy.md.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from low_sun_montecarlo_reference import ATMOSPHERES, directions, views  # noqa: E402  (a sibling script)
from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.montecarlo import sky_radiance
from skyscatter.precomputed import cached_atmosphere

MORE = {
    "rayleigh": lambda: AtmosphereParameters(mie_angstrom_beta=0.0, ozone_column=0.0),
    "noozone": lambda: AtmosphereParameters(ozone_column=0.0),
}
WINDOWS = {"o1": 1, "o2": 2, "o3+": (3, None)}


def atmosphere(name: str) -> AtmosphereParameters:
    return MORE[name]() if name in MORE else ATMOSPHERES[name][1]()


def monte_carlo(name: str, sun: float, paths: int, seed: int, wl: list[float], cache: Path | None) -> dict:
    """Radiance and standard error of each window (n_views, n_wavelengths) [W m^-2 sr^-1 nm^-1]."""
    key = f"{name}_{sun:g}_{paths}_{seed}_" + "-".join(f"{w:g}" for w in wl)
    path = None if cache is None else cache / f"mc_by_order_{key}.npz"
    if path is not None and path.exists():
        z = np.load(path)
        return {k: (z[k], z[k + "_se"]) for k in WINDOWS}
    out = {}
    for k, window in WINDOWS.items():
        t0 = time.perf_counter()
        mc = sky_radiance(atmosphere(name), directions(), wl, sun_zenith=math.radians(90.0 - sun), samples=paths,
                          seed=seed, orders=window)
        out[k] = (mc.radiance, mc.stderr)
        print(f"# Monte Carlo {name} sun {sun:+g} deg window {k}: {time.perf_counter() - t0:.0f} s", flush=True)
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez(path, **{k: v[0] for k, v in out.items()}, **{k + "_se": v[1] for k, v in out.items()})
    return out


def tables(name: str, sun: float, wl: list[float], sizes: dict | None) -> dict:
    atm = atmosphere(name)
    s = math.radians(sun)
    sun_dir = np.array([0.0, math.cos(s), math.sin(s)])
    pos = np.array([0.0, 0.0, atm.bottom_radius])
    r = {n: cached_atmosphere(atm, wavelengths=wl, orders=n, sizes=sizes, progress=False)
         .sky_radiance(pos, directions(), sun_dir) for n in (1, 2, 8)}
    return {"o1": r[1], "o2": r[2] - r[1], "o3+": r[8] - r[2]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--atm", default="earth", choices=sorted([*ATMOSPHERES, *MORE]))
    ap.add_argument("--sun", type=float, default=-3.0, help="sun elevation [deg]")
    ap.add_argument("--paths", type=int, default=2097152, help="Monte Carlo paths per direction and window")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--wavelengths", default="400,560,700", help="[nm]")
    ap.add_argument("--sizes", default="", help="table size overrides, e.g. scattering_nu=15,scattering_mu_s=64")
    ap.add_argument("--mc-cache", type=Path, default=None, help="folder keeping the Monte Carlo runs")
    args = ap.parse_args()
    wl = [float(w) for w in args.wavelengths.split(",")]
    sizes = {k: int(v) for k, v in (kv.split("=") for kv in args.sizes.split(",") if kv)} or None
    mc = monte_carlo(args.atm, args.sun, args.paths, args.seed, wl, args.mc_cache)
    tab = tables(args.atm, args.sun, wl, sizes)
    total = sum(v[0] for v in mc.values())
    print(f"{args.atm}, sun {args.sun:+g} deg, sizes {args.sizes or 'default'}: 100 (tables / MC - 1) [%] "
          "(difference / MC standard error)")
    print("view    " + "".join(f"{k}@{w:.0f}".rjust(15) for k in WINDOWS for w in wl) + "   MC shares o1/o2/o3+ "
          f"@{wl[-1]:.0f}")
    for i, (e, a) in enumerate(views()):
        cells = []
        for k in WINDOWS:
            m, se = mc[k]
            for j in range(len(wl)):
                rel = 100 * (tab[k][i, j] / m[i, j] - 1) if m[i, j] > 0 else math.nan
                z = (tab[k][i, j] - m[i, j]) / se[i, j] if se[i, j] > 0 else math.nan
                cells.append(f"{rel:+7.1f}({z:+5.1f})")
        shares = "/".join(f"{mc[k][0][i, -1] / total[i, -1]:.2f}" for k in WINDOWS)
        print(f"{e:2.0f}/{a:3.0f}  " + "".join(c.rjust(15) for c in cells) + "   " + shares)
    for k in WINDOWS:
        m, se = mc[k]
        ok = np.all(m > 0, axis=1)
        rel = 100 * (tab[k][ok] / m[ok] - 1)
        z = (tab[k][ok] - m[ok]) / se[ok]
        print(f"  {k}: over {int(ok.sum())} views mean " + " / ".join(f"{v:+.2f}" for v in rel.mean(axis=0))
              + " %, median " + " / ".join(f"{v:+.2f}" for v in np.median(rel, axis=0))
              + " %, mean z " + " / ".join(f"{v:+.2f}" for v in z.mean(axis=0)))


if __name__ == "__main__":
    main()
