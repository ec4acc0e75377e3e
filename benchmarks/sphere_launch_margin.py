"""Is the sphere's forward-photon reference short of light launched outside its annulus? The launch margin widened.

:func:`skyscatter.montecarlo.sphere.sphere_ground_fluxes` launches photons over an annulus of impact parameters
holding every ray through the air above the tallied rings plus a margin (default 3 deg) on both sides, for light
carried sideways and back (docs/clouds.md, "Forward photons in the sphere": "The annulus"). Light from rays landing
beyond the margin is left out by construction; this script measures how much by running the same ring with the
default margin and a wider one (independent seeds) and printing the difference with its standard error.

``nice -n 19 python benchmarks/sphere_launch_margin.py --tau 15 --sun 2 --wavelength 550 --photons 12000000
--margins 3,6 --seeds 501,502`` (each margin with each seed; the water cloud 1000-1500 m, r_e 10 um, ground albedo
0.2, Earth defaults: the cases of ``cloudy_sphere_reference.py``). ``--json FILE`` also writes the figures
(the run of 2026-12-05: ``sphere_launch_margin_tau15_sun2.json`` here).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.atmosphere.clouds import CloudLayer
from skyscatter.fileio import atomic_path
from skyscatter.montecarlo.sphere import sphere_ground_fluxes

BASE, TOP, ALBEDO, RING_HALF_DEG = 1000.0, 1500.0, 0.2, 0.25


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tau", type=float, default=15.0, help="cloud optical depth at 550 nm [-] (0: clear air)")
    ap.add_argument("--sun", type=float, default=2.0, help="the ring's sun elevation [deg]")
    ap.add_argument("--wavelength", type=float, default=550.0, help="[nm]")
    ap.add_argument("--photons", type=int, default=4_000_000, help="per run")
    ap.add_argument("--margins", default="3,6", help="launch margins [deg], comma-separated")
    ap.add_argument("--seeds", default="501", help="seeds, comma-separated (each margin runs every seed)")
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    clear = AtmosphereParameters(ground_albedo=ALBEDO)
    atm = clear.replace(particles=(CloudLayer(BASE, TOP, a.tau),)) if a.tau > 0 else clear
    edges = np.radians([a.sun - RING_HALF_DEG, a.sun + RING_HALF_DEG])
    margins = [float(v) for v in a.margins.split(",")]
    seeds = [int(v) for v in a.seeds.split(",")]
    runs = []
    for seed in seeds:
        for k, m in enumerate(margins):
            c0 = time.process_time()
            r = sphere_ground_fluxes(atm, [a.wavelength], elevation_edges=edges, photons=a.photons,
                                     margin=math.radians(m), seed=seed * 100 + k)
            cpu = time.process_time() - c0
            runs.append({"margin_deg": m, "seed": seed * 100 + k, "photons": r.photons,
                         "diffuse": float(r.diffuse[0, 0]), "diffuse_stderr": float(r.diffuse_stderr[0, 0]),
                         "cpu_seconds": cpu, "load_average": os.getloadavg()[0]})
            print(f"margin {m:g} deg seed {seed * 100 + k}: diffuse {r.diffuse[0, 0]:.6g} +- "
                  f"{100 * r.diffuse_stderr[0, 0] / r.diffuse[0, 0]:.2f} %, {cpu:.0f} CPU-s, "
                  f"load {os.getloadavg()[0]:.1f}", flush=True)
    pooled = {}
    for m in margins:
        mine = [r for r in runs if r["margin_deg"] == m]
        n = np.array([r["photons"] for r in mine], float)
        v = np.array([r["diffuse"] for r in mine])
        s = np.array([r["diffuse_stderr"] for r in mine])
        mean = float(np.sum(n * v) / n.sum())
        err = float(np.sqrt(np.sum((n * s) ** 2)) / n.sum())
        pooled[m] = (mean, err)
        print(f"margin {m:g} deg pooled: {mean:.6g} +- {100 * err / mean:.2f} %")
    base = margins[0]
    for m in margins[1:]:
        d = pooled[m][0] / pooled[base][0] - 1.0
        e = math.hypot(pooled[m][1] / pooled[m][0], pooled[base][1] / pooled[base][0]) * (1 + d)
        print(f"margin {m:g} vs {base:g} deg: {100 * d:+.2f} +- {100 * e:.2f} % ({d / e:+.1f} sigma)")
    if a.json:
        with atomic_path(Path(a.json)) as tmp:
            Path(tmp).write_text(json.dumps({"args": vars(a), "runs": runs,
                                             "pooled": {str(k): v for k, v in pooled.items()}}, indent=1) + "\n")


if __name__ == "__main__":
    main()
