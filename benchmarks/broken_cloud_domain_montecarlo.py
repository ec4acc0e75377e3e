"""Monte Carlo domain-mean ground irradiance of the broken cloud fields, and their radiance seen from above: the
reference the ``broken-cloud`` sky model's :meth:`~skyscatter.sky.broken_cloud.BrokenCloudSky.ground_irradiance`
and its view from 10 km are compared with (tests/data/broken_cloud_domain_montecarlo.json and
tests/data/broken_cloud_above_montecarlo.npz).

Scene: the fields of ``benchmarks/broken_cloud_montecarlo.py`` (``field_for``: procedural, cover 0.3, 0.6 and 0.9,
1000-2500 m, mean optical depth 10 of the cloudy columns, 16 km periodic at 64 x 64 x 16 voxels, features 4 km,
field seed 3, Mie droplets 10 um), Earth air, ground albedo 0.2, 450 / 550 / 650 nm (hero wavelengths).

* ``irradiance``: forward photons over the periodic domain
  (:func:`skyscatter.montecarlo.domain.domain_quantities` with a flux level at the ground, ``samples`` photons per
  column, no radiances): the domain-mean downward irradiance at the ground, direct (deterministic, 4 x 4 points
  per column along the sun's centre) and diffuse (with its standard error from the batches), / (mu0 F0), at sun
  elevations 30 and 60 deg, azimuth 135 deg. Written to the JSON after each case (atomically), with the seeds.
* ``above``: backward paths from 10 km above the observer's foot point (``sky_radiance(..., altitude=10000)``)
  along the pixels of a 32 x 32 equidistant fisheye looking straight down (the upward fisheye's directions with
  ``z`` negated: north at the top, east on the left as seen from below, i.e. the map seen through the floor),
  sun zenith 55 deg, azimuth 135 deg (the scene of the fisheye from the ground), ``--samples`` paths per pixel.

Usage: ``python benchmarks/broken_cloud_domain_montecarlo.py irradiance [--photons 16] [--seed 3301]`` and
``python benchmarks/broken_cloud_domain_montecarlo.py above [--samples 1024] [--seed 3401]``; one thread
(``scheduler="synchronous"``) unless ``--threads``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from broken_cloud_montecarlo import COVERS, SCENE, WAVELENGTHS, field_for  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.conventions import fisheye_directions  # noqa: E402
from skyscatter.fileio import atomic_path  # noqa: E402
from skyscatter.montecarlo import sky_radiance  # noqa: E402
from skyscatter.montecarlo.domain import domain_quantities  # noqa: E402

DATA = Path(__file__).parents[1] / "tests" / "data"
IRRADIANCE = DATA / "broken_cloud_domain_montecarlo.json"
ABOVE = DATA / "broken_cloud_above_montecarlo.npz"
SUN_ELEVATIONS_DEG = (30.0, 60.0)
SUN_AZIMUTH_DEG = 135.0
ABOVE_ALTITUDE = 10_000.0


def nadir_fisheye(size: int) -> tuple[np.ndarray, np.ndarray]:
    """Directions (size, size, 3) of an equidistant fisheye looking straight down and its disc mask."""
    d, inside = fisheye_directions(size)
    d = d.copy()
    d[..., 2] *= -1.0
    return d, inside


def _write_json(path: Path, obj: dict) -> None:
    with atomic_path(path) as tmp:
        Path(tmp).write_text(json.dumps(obj, indent=1) + "\n")


def irradiance(args) -> None:
    air = AtmosphereParameters(ground_albedo=SCENE["ground_albedo"])
    out = json.loads(args.out.read_text()) if args.out.exists() and args.resume else {}
    scene = {k: v for k, v in SCENE.items() if k != "sun_zenith_deg"}  # each case has its own sun
    out.setdefault("scene", dict(scene, sun_azimuth_deg=SUN_AZIMUTH_DEG,
                                 script="benchmarks/broken_cloud_domain_montecarlo.py irradiance",
                                 wavelengths_nm=WAVELENGTHS.tolist(), photons_per_column=args.photons,
                                 direct_points=4))
    cases = out.setdefault("cases", {})
    k = 0
    for elev in args.elevations:
        for cover in COVERS:
            key = f"cover {cover} sun {elev:g}"
            seed = args.seed + k
            k += 1
            if key in cases:
                continue
            field = field_for(cover)
            t0 = time.perf_counter()
            r = domain_quantities(air, field, WAVELENGTHS, sun_zenith=math.radians(90.0 - elev),
                                  sun_azimuth=math.radians(SUN_AZIMUTH_DEG), up_views=None, samples=args.photons,
                                  seed=seed, direct_points=4, levels=[0.0], scheduler=args.scheduler)
            secs = time.perf_counter() - t0
            g = int(np.flatnonzero(r.levels == 0.0)[0])
            n = r.level_down.shape[1] * r.level_down.shape[2]
            down = r.level_down[g].mean(axis=(0, 1))
            down_se = np.sqrt(np.sum(r.level_down_stderr[g] ** 2, axis=(0, 1))) / n
            direct = r.level_direct[g].mean(axis=(0, 1))
            up_top = r.level_up[-1].mean(axis=(0, 1))
            cases[key] = {"cover": cover, "sun_elevation_deg": elev, "seed": seed, "photons": int(r.photons),
                          "cloud_fraction": round(float(field.cloud_fraction()), 4),
                          "global": down.tolist(), "global_stderr": down_se.tolist(), "direct": direct.tolist(),
                          "diffuse": (down - direct).tolist(), "reflectance_top": up_top.tolist(),
                          "mean_vertices": round(float(r.mean_vertices), 2), "seconds": round(secs, 1),
                          "load_average": round(os.getloadavg()[0], 1)}
            _write_json(args.out, out)
            print(f"{key}: global {np.round(down, 4)} +- {np.round(down_se, 4)}, direct {np.round(direct, 4)}, "
                  f"{r.photons} photons, {r.mean_vertices:.1f} events, {secs:.0f} s (load {os.getloadavg()[0]:.1f})",
                  flush=True)


def above(args) -> None:
    air = AtmosphereParameters(ground_albedo=SCENE["ground_albedo"])
    d, inside = nadir_fisheye(args.size)
    dirs = d[inside]
    prev = dict(np.load(args.out)) if args.out.exists() and args.resume else {}
    out: dict = {"directions": dirs, "inside": inside, "wavelengths": WAVELENGTHS, "covers": np.array(COVERS)}
    meta = dict(SCENE, size_px=args.size, samples=args.samples, altitude=ABOVE_ALTITUDE,
                seeds=[args.seed + i for i in range(len(COVERS))],
                script="benchmarks/broken_cloud_domain_montecarlo.py above")
    if "meta" in prev:
        meta.update({k: v for k, v in json.loads(str(prev["meta"])).items() if k.startswith(("paths_", "seconds_"))})
    for i, cover in enumerate(COVERS):
        if f"radiance_{i}" in prev:
            out[f"radiance_{i}"], out[f"stderr_{i}"] = prev[f"radiance_{i}"], prev[f"stderr_{i}"]
            continue
        t0 = time.perf_counter()
        res = sky_radiance(air, dirs, WAVELENGTHS, sun_zenith=math.radians(SCENE["sun_zenith_deg"]),
                           sun_azimuth=math.radians(SCENE["sun_azimuth_deg"]), altitude=ABOVE_ALTITUDE,
                           samples=args.samples, seed=args.seed + i, clouds=field_for(cover),
                           scheduler=args.scheduler)
        secs = time.perf_counter() - t0
        out[f"radiance_{i}"], out[f"stderr_{i}"] = res.radiance, res.stderr
        meta[f"paths_{i}"] = int(res.samples)
        meta[f"seconds_{i}"] = round(secs, 1)
        out["meta"] = np.array(json.dumps(meta))
        with atomic_path(args.out) as tmp:
            with open(tmp, "wb") as fh:
                np.savez_compressed(fh, **out)
        print(f"above, cover {cover}: {res.samples} paths per pixel, {res.mean_vertices:.1f} events per path, "
              f"median relative stderr {np.median(res.stderr / np.maximum(res.radiance, 1e-30)):.3f}, {secs:.0f} s "
              f"(load {os.getloadavg()[0]:.1f})", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what", required=True)
    a = sub.add_parser("irradiance", help="domain-mean ground irradiance by forward photons")
    a.add_argument("--photons", type=int, default=16, help="forward photons per column (4096 columns)")
    a.add_argument("--seed", type=int, default=3301, help="seed of the first case (+1 per case)")
    a.add_argument("--elevations", type=float, nargs="+", default=list(SUN_ELEVATIONS_DEG), help="[deg]")
    a.add_argument("--out", type=Path, default=IRRADIANCE)
    b = sub.add_parser("above", help="radiance of a nadir fisheye from 10 km")
    b.add_argument("--size", type=int, default=32, help="fisheye width [px]")
    b.add_argument("--samples", type=int, default=1024, help="paths per pixel")
    b.add_argument("--seed", type=int, default=3401, help="Monte Carlo seed (cover i uses seed + i)")
    b.add_argument("--out", type=Path, default=ABOVE)
    for p in (a, b):
        p.add_argument("--resume", action="store_true", help="keep the cases already in --out")
        p.add_argument("--threads", action="store_true", help="dask's threaded scheduler instead of one thread")
    args = ap.parse_args()
    args.scheduler = None if args.threads else "synchronous"
    print(f"machine: {len(os.sched_getaffinity(0))} cores, load average {os.getloadavg()[0]:.1f}", flush=True)
    (irradiance if args.what == "irradiance" else above)(args)


if __name__ == "__main__":
    main()
