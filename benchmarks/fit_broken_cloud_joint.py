"""Joint fit of the ``broken-cloud`` sky's octaves ``(a, b, c, e)`` against all of its accuracy guards at once.

The guards are the tests' (tests/test_broken_cloud.py, tests/test_broken_cloud_irradiance.py; docs/clouds.md),
each as a *margin* (the figure over its tolerance; a guard passes below 1):

* ``uniform_median`` / ``uniform_max``: a one-column field of optical depth 5 at 1000-1500 m (an exact infinite
  layer), sun 30 deg from the zenith, against the DISORT ``cloudy`` layer model (computed once here) over the 14
  directions 20 deg or more from the sun: the median of ``model / DISORT - 1`` per wavelength within 0.20, every
  direction within 0.45;
* ``fisheye_mean`` / ``fisheye_rms`` / ``fisheye_region``: the fisheye from the ground against the stored Monte Carlo
  (tests/data/broken_cloud_montecarlo.npz), covers 0.3 / 0.6 / 0.9: disc means within 10 %, per-pixel RMS of the
  relative difference below 0.8, the 15 region means (those of 20 pixels or more) within [0.35, 1.7] (margin:
  the larger of ``0.35 / min`` and ``max / 1.7``);
* ``irradiance``: the domain-mean global ground irradiance of the six stored Monte Carlo cases
  (tests/data/broken_cloud_domain_montecarlo.json, covers 0.3 / 0.6 / 0.9, sun 30 / 60 deg high) within 5 %
  (the issue's target), at the test's quadrature (4 x 4 points x 16 x 32 directions);
* ``above_mean`` / ``above_rms``: the nadir fisheye from 10 km (tests/data/broken_cloud_above_montecarlo.npz): disc
  means within 22 %, per-pixel RMS below 0.40.

All at 450 / 550 / 650 nm, ``interpolation="voxel"``, the delta-M truncation ``--truncation-streams`` (default 16;
``skyscatter.sky.broken_cloud.TRUNCATION_STREAMS``). The search minimises the largest margin (minimax; all guards
pass below 1; plus 0.01 times the sum of the squared margins, to break ties) by Nelder-Mead (scipy) over
``--free`` from ``--x0`` (initial simplex edges ``--step``), every evaluation cached in ``--out`` (a rerun
continues from it; ``best`` the evaluation of the smallest largest margin). ``--eval a b c d e [...]`` evaluates
those octaves only. Usage: ``python benchmarks/fit_broken_cloud_joint.py [--x0 a b c d e] [--free a b c e]
[--max-nfev N] [--eval ...]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from functools import cache
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from broken_cloud_domain_montecarlo import ABOVE, ABOVE_ALTITUDE, IRRADIANCE  # noqa: E402
from broken_cloud_montecarlo import OUT as DATA  # noqa: E402
from broken_cloud_montecarlo import field_for  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.atmosphere.clouds import CloudField, CloudLayer  # noqa: E402
from skyscatter.conventions import direction_from_angles  # noqa: E402
from skyscatter.sky import broken_cloud  # noqa: E402
from skyscatter.sky.broken_cloud import BrokenCloudSky  # noqa: E402

RESULT = Path(__file__).with_suffix(".json")
NAMES = ("a", "b", "c", "d", "e")
LOWER = np.array([0.01, 0.0, 0.0, 0.0, 0.0])
UPPER = np.array([1.0, 0.99, 1.0, 2.0, 2.0])
WL = np.array([450.0, 550.0, 650.0])
#: Tolerances of the guards (the tests').
TOL = {"uniform_median": 0.20, "uniform_max": 0.45, "fisheye_mean": 0.10, "fisheye_rms": 0.8,
       "irradiance": 0.05, "above_mean": 0.22, "above_rms": 0.40}


class Scenes:
    """Every guard's skies, built once (their shadow volumes and tables); the octaves are set per evaluation."""

    def __init__(self) -> None:
        data = np.load(DATA)
        meta = json.loads(str(data["meta"]))
        air = AtmosphereParameters(ground_albedo=meta["ground_albedo"])
        covers = [float(c) for c in data["covers"]]
        self.fish = [(BrokenCloudSky(math.radians(meta["sun_zenith_deg"]), math.radians(meta["sun_azimuth_deg"]),
                                     clouds=field_for(c, meta), atmosphere=air, interpolation="voxel"),
                      data[f"radiance_{i}"]) for i, c in enumerate(covers)]
        self.fish_dirs = data["directions"]
        sun = self.fish[0][0].sun_direction
        d = self.fish_dirs
        self.fish_region = np.digitize(d @ sun, [0.0, 0.5, 0.8, 0.95]) * 3 + np.digitize(d[:, 2], [0.3, 0.6])
        up = np.load(ABOVE)
        ameta = json.loads(str(up["meta"]))
        aair = AtmosphereParameters(ground_albedo=ameta["ground_albedo"])
        self.above = [(BrokenCloudSky(math.radians(ameta["sun_zenith_deg"]), math.radians(ameta["sun_azimuth_deg"]),
                                      clouds=field_for(c, ameta), atmosphere=aair, altitude=ABOVE_ALTITUDE,
                                      interpolation="voxel"), up[f"radiance_{i}"])
                      for i, c in enumerate(float(c) for c in up["covers"])]
        self.above_dirs = up["directions"]
        dom = json.loads(IRRADIANCE.read_text())
        scene = dom["scene"]
        dair = AtmosphereParameters(ground_albedo=scene["ground_albedo"])
        self.irr = {}
        for key, case in dom["cases"].items():
            zen = math.radians(90.0 - case["sun_elevation_deg"])
            s = BrokenCloudSky(zen, math.radians(scene["sun_azimuth_deg"]), clouds=field_for(case["cover"], scene),
                               atmosphere=dair, interpolation="voxel")
            norm = math.cos(zen) * np.asarray(dair.solar_irradiance_at(WL), dtype=float)
            self.irr[key] = (s, norm, np.asarray(case["global"]))
        # the uniform layer (tests/test_broken_cloud.py, _uniform_layer_against_disort)
        from skyscatter.sky.cloudy import CloudySky

        drops = CloudLayer(0.0, 1.0, 1.0, effective_radius=10e-6)
        sz, sa = math.radians(30.0), math.radians(135.0)
        field = CloudField(np.full((1, 1, 8), 5.0 / 500.0), 1000.0, 1000.0, 1500.0, drops)
        self.layer = BrokenCloudSky(sz, sa, clouds=field, interpolation="voxel")
        dd = np.array([direction_from_angles(math.radians(90.0 - e), math.radians(a))
                       for e in (15, 40, 65, 90) for a in (0, 135, 250, 315)])
        self.layer_dirs = dd[np.degrees(np.arccos(np.clip(dd @ self.layer.sun_direction, -1, 1))) >= 20.0]
        c = CloudySky(sz, sa, cloud_optical_depth=5.0, cloud_base=1000.0, cloud_top=1500.0)
        self.layer_ref = c.spectral_radiance(self.layer_dirs, WL)

    def figures(self, theta: tuple[float, ...]) -> dict:
        """Every guard's figures (per wavelength) and margins for the octaves ``theta`` = (a, b, c, d, e)."""
        out: dict = {}
        self.layer.octaves = theta
        rel = self.layer.spectral_radiance(self.layer_dirs, WL) / self.layer_ref - 1.0
        out["uniform_median"] = np.median(rel, axis=0).round(4).tolist()
        out["uniform_max"] = np.abs(rel).max(axis=0).round(4).tolist()
        means, rms, reg_lo, reg_hi = [], [], [], []
        for sky, mc in self.fish:
            sky.octaves = theta
            model = sky.spectral_radiance(self.fish_dirs, WL)
            means.append((model.mean(axis=0) / mc.mean(axis=0)).round(4).tolist())
            rms.append(np.sqrt(np.mean((model / mc - 1.0) ** 2, axis=0)).round(4).tolist())
            rr = [model[s].mean(axis=0) / mc[s].mean(axis=0) for r in np.unique(self.fish_region)
                  if (s := self.fish_region == r).sum() >= 20]
            reg_lo.append(round(float(np.min(rr)), 4))
            reg_hi.append(round(float(np.max(rr)), 4))
        out.update(fisheye_mean=means, fisheye_rms=rms, fisheye_region_min=reg_lo, fisheye_region_max=reg_hi)
        irr = {}
        for key, (sky, norm, mc_g) in self.irr.items():
            sky.octaves = theta
            direct, diffuse = sky.domain_ground_irradiance(WL, points_per_axis=4, zeniths=16, azimuths=32)
            irr[key] = ((direct + diffuse) / norm / mc_g).round(4).tolist()
        out["irradiance"] = irr
        amean, arms = [], []
        for sky, mc in self.above:
            sky.octaves = theta
            model = sky.spectral_radiance(self.above_dirs, WL)
            amean.append((model.mean(axis=0) / mc.mean(axis=0)).round(4).tolist())
            arms.append(np.sqrt(np.mean((model / mc - 1.0) ** 2, axis=0)).round(4).tolist())
        out.update(above_mean=amean, above_rms=arms)
        out["margins"] = margins(out)
        out["worst"] = max(out["margins"].values())
        return out


def margins(f: dict) -> dict:
    """Each guard's figure over its tolerance (the guard passes below 1)."""
    dev = lambda v: float(np.max(np.abs(np.asarray(v) - 1.0)))  # noqa: E731
    return {"uniform_median": round(float(np.max(np.abs(f["uniform_median"]))) / TOL["uniform_median"], 4),
            "uniform_max": round(float(np.max(f["uniform_max"])) / TOL["uniform_max"], 4),
            "fisheye_mean": round(dev(f["fisheye_mean"]) / TOL["fisheye_mean"], 4),
            "fisheye_rms": round(float(np.max(f["fisheye_rms"])) / TOL["fisheye_rms"], 4),
            "fisheye_region": round(max(0.35 / min(f["fisheye_region_min"]), max(f["fisheye_region_max"]) / 1.7), 4),
            "irradiance": round(dev(list(f["irradiance"].values())) / TOL["irradiance"], 4),
            "above_mean": round(dev(f["above_mean"]) / TOL["above_mean"], 4),
            "above_rms": round(float(np.max(f["above_rms"])) / TOL["above_rms"], 4)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--x0", type=float, nargs=5, default=[0.4559, 0.68, 0.6411, 0.0, 0.5], help="start (a..e)")
    ap.add_argument("--free", nargs="+", choices=list(NAMES), default=["a", "b", "c", "e"])
    ap.add_argument("--max-nfev", type=int, default=30, help="at most this many evaluations of the search")
    ap.add_argument("--eval", type=float, nargs="+", help="evaluate these octaves (groups of 5) only")
    ap.add_argument("--step", type=float, nargs=5, default=[0.02, 0.01, 0.03, 0.1, 0.1],
                    help="the initial simplex's edges along a, b, c, d, e")
    ap.add_argument("--truncation-streams", type=int, default=16)
    ap.add_argument("--out", type=Path, default=RESULT)
    args = ap.parse_args()
    broken_cloud.TRUNCATION_STREAMS = args.truncation_streams
    store = json.loads(args.out.read_text()) if args.out.exists() else {}
    runs = store.setdefault(f"truncation_{args.truncation_streams}", {})
    t0, c0 = time.perf_counter(), time.process_time()
    scenes = Scenes()
    print(f"scenes built: {time.perf_counter() - t0:.0f} s wall, {time.process_time() - c0:.0f} CPU-s, "
          f"load {os.getloadavg()[0]:.1f}", flush=True)

    @cache
    def evaluate(theta: tuple[float, ...]) -> dict:
        key = " ".join(f"{v:.4f}" for v in theta)
        if key in runs:
            return runs[key]
        c1 = time.process_time()
        fig = scenes.figures(theta)
        fig["cpu_seconds"] = round(time.process_time() - c1, 1)
        fig["load_average"] = round(os.getloadavg()[0], 1)
        runs[key] = fig
        args.out.write_text(json.dumps(store, indent=1) + "\n")
        print(f"{key}: worst {fig['worst']:.3f} {fig['margins']} ({fig['cpu_seconds']} CPU-s, load "
              f"{fig['load_average']})", flush=True)
        return fig

    if args.eval:
        for i in range(0, len(args.eval), 5):
            evaluate(tuple(round(v, 4) for v in args.eval[i:i + 5]))
        return
    from scipy.optimize import minimize

    start = np.array(args.x0)
    free = [NAMES.index(n) for n in args.free]

    def objective(x: np.ndarray) -> float:
        theta = start.copy()
        theta[free] = np.clip(x, LOWER[free], UPPER[free])
        fig = evaluate(tuple(round(float(v), 4) for v in theta))
        # the largest margin, ties broken towards smaller margins everywhere
        return fig["worst"] + 0.01 * float(np.sum(np.square(list(fig["margins"].values()))))

    step = np.array(args.step)[free]
    simplex = [start[free]] + [start[free] + np.eye(len(free))[j] * step for j in range(len(free))]
    res = minimize(objective, start[free], method="Nelder-Mead",
                   options={"maxfev": args.max_nfev, "initial_simplex": np.array(simplex), "xatol": 2e-3,
                            "fatol": 2e-3})
    theta = start.copy()
    theta[free] = np.clip(res.x, LOWER[free], UPPER[free])
    best = min(runs.items(), key=lambda kv: kv[1]["worst"])
    store["best"] = {"octaves": best[0], **best[1]}
    args.out.write_text(json.dumps(store, indent=1) + "\n")
    print(f"best: {best[0]} worst margin {best[1]['worst']} {best[1]['margins']}")


if __name__ == "__main__":
    main()
