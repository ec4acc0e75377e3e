"""CPU time of the clear sky's march alone against an older commit's (default 663eefd, the kernels before the clouds).

The older ``src/skyscatter`` is extracted (``git archive``) into a temporary folder as the package ``skyscatter_old``
(as ``bench_montecarlo_clear_ab.py`` does) and a loop compiled in this process calls each march over the same random
rays of the clear air (Earth defaults, 11 wavelengths 360-760 nm, the hero's coefficients per ray): origins at
altitudes uniform in 0-20 km, directions uniform on the sphere, to the ground or the top. ``free``: the free paths'
march (a target ``-ln(1 - u)``, located in its piece: the old ``_march``, the clear kernel's ``_march3_locate``);
``shadow``: the shadow rays' march (the old ``_march`` with no target, the clear kernel's ``_march3_columns`` and its
test of the least extinguished wavelength's depth against ``_NEE_STOP``, ``_opaque3``). Rounds alternate old and
new; prints best and median CPU time per round and their ratio, and whether the columns agree to the bit. Delete the
tree's numba cache first (``find src -name '*.nb[ic]' -delete``): both are compiled in the process.
Usage: ``python benchmarks/bench_march_ab.py [--commit REV] [--rays N] [--rounds N] [--repeat N]``.
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

import numba
import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.montecarlo import driver, kernels

WAVELENGTHS = np.arange(360.0, 761.0, 40.0)


def _old_kernels(commit: str, root: Path):
    repo = Path(__file__).resolve().parents[1]
    archive = subprocess.run(["git", "-C", str(repo), "archive", commit, "src/skyscatter"], check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(root)], input=archive, check=True)
    shutil.move(str(root / "src" / "skyscatter"), str(root / "skyscatter_old"))
    sys.path.insert(0, str(root))
    return importlib.import_module("skyscatter_old.montecarlo.kernels")


def _rays(n: int, rb: float, seed: int = 7):
    rng = np.random.default_rng(seed)
    h = rng.uniform(0.0, 20e3, n)
    u = rng.normal(size=(n, 3))
    p = u / np.linalg.norm(u, axis=1)[:, None] * (rb + h)[:, None]
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return p, d, rng.uniform(size=n), rng.integers(0, WAVELENGTHS.size, n)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--commit", default="663eefd")
    ap.add_argument("--rays", type=int, default=20000)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--repeat", type=int, default=5, help="passes over the rays per round")
    args = ap.parse_args()
    m = driver.prepare_medium(AtmosphereParameters(), WAVELENGTHS)
    rb, rt, edges, layers, nlay, coef = m.bottom_radius, m.top_radius, m.edges, m.layers, m.nlay, m.coef
    assert coef.shape[1] == 3, "the clear sky's three components"
    kmin = coef.min(axis=0)
    pts, dirs, us, heroes = _rays(args.rays, rb)
    with tempfile.TemporaryDirectory() as tmp:
        old = _old_kernels(args.commit, Path(tmp))
        o_march, o_exit = old._march, old._exit_distance
        n_exit = kernels._exit_distance

        @numba.njit(nogil=True, error_model="numpy")
        def loop_old(pts, dirs, us, heroes, coef, kmin, rb, rt, edges, layers, nlay, shadow, repeat, out):
            cols = np.zeros(3)
            tmp = np.zeros(3)
            rec = np.zeros((2 * edges.shape[0] + 2, 5))
            for _ in range(repeat):
                for i in range(pts.shape[0]):
                    px, py, pz = pts[i, 0], pts[i, 1], pts[i, 2]
                    dx, dy, dz = dirs[i, 0], dirs[i, 1], dirs[i, 2]
                    te, _g = o_exit(px, py, pz, dx, dy, dz, rb, rt)
                    if shadow:
                        t, _r, _n = o_march(px, py, pz, dx, dy, dz, te, np.inf, 0.0, 0.0, 0.0, rb, edges, layers, nlay,
                                            cols, tmp, rec)
                    else:
                        h = heroes[i]
                        t, _r, _n = o_march(px, py, pz, dx, dy, dz, te, -math.log1p(-us[i]), coef[h, 0], coef[h, 1],
                                            coef[h, 2], rb, edges, layers, nlay, cols, tmp, rec)
                    out[i, 0] = t
                    out[i, 1] = cols[0]
                    out[i, 2] = cols[1]
                    out[i, 3] = cols[2]

        m3_locate, m3_columns, m3_opaque = kernels._march3_locate, kernels._march3_columns, kernels._opaque3

        @numba.njit(nogil=True, error_model="numpy")
        def loop_new3(pts, dirs, us, heroes, coef, kmin, rb, rt, edges, layers, nlay, shadow, repeat, out):
            cols = np.zeros(3)
            tmp = np.zeros(3)
            rec = np.zeros((2 * edges.shape[0] + 2, 5))
            for _ in range(repeat):
                for i in range(pts.shape[0]):
                    px, py, pz = pts[i, 0], pts[i, 1], pts[i, 2]
                    dx, dy, dz = dirs[i, 0], dirs[i, 1], dirs[i, 2]
                    te, _g = n_exit(px, py, pz, dx, dy, dz, rb, rt)
                    if shadow:
                        m3_columns(px, py, pz, dx, dy, dz, te, rb, edges, layers, nlay, cols, tmp, rec)
                        t = te if not m3_opaque(kmin, cols) else 0.0
                    else:
                        h = heroes[i]
                        t, _r, _n = m3_locate(px, py, pz, dx, dy, dz, te, -math.log1p(-us[i]), coef[h, 0], coef[h, 1],
                                              coef[h, 2], rb, edges, layers, nlay, cols, tmp, rec)
                    out[i, 0] = t
                    out[i, 1] = cols[0]
                    out[i, 2] = cols[1]
                    out[i, 3] = cols[2]

        fns = {"old": loop_old, "new": loop_new3}
        for mode in ("free", "shadow"):
            shadow = mode == "shadow"
            outs = {}
            for name, fn in fns.items():
                outs[name] = np.zeros((pts.shape[0], 4))
                fn(pts, dirs, us, heroes, coef, kmin, rb, rt, edges, layers, nlay, shadow, 1, outs[name])
            same = np.array_equal(outs["old"], outs["new"])
            times = {k: [] for k in fns}
            for _r in range(args.rounds):
                for name, fn in fns.items():
                    c0 = time.process_time()
                    fn(pts, dirs, us, heroes, coef, kmin, rb, rt, edges, layers, nlay, shadow, args.repeat, outs[name])
                    times[name].append(time.process_time() - c0)
            bo, bn = min(times["old"]), min(times["new"])
            mo, mn = float(np.median(times["old"])), float(np.median(times["new"]))
            ratios = sorted(n / o for n, o in zip(times["new"], times["old"], strict=True))
            print(f"{mode}: old best {bo:.3f} median {mo:.3f} CPU-s, new best {bn:.3f} median {mn:.3f}; new / old "
                  f"best {bn / bo:.3f}, median {mn / mo:.3f}, per-round median {np.median(ratios):.3f}; columns "
                  f"identical: {same}; load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
