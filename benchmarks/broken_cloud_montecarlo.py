"""Monte Carlo radiances of broken cloud fields seen from the ground: the reference the ``broken-cloud`` sky model's
multiple-scattering parameters are fitted to and tested against (tests/data/broken_cloud_montecarlo.npz).

Scene (docs/clouds.md, "Broken cloud fields in images"): procedural fields (``CloudField.procedural``: cover 0.3,
0.6 and 0.9, base 1000 m, highest tops 2500 m, mean optical depth 10 of the cloudy columns, a periodic domain of
16 km at 64 x 64 x 16 voxels, feature size 4 km, field seed 3) of Mie water droplets (r_e 10 um, effective
variance 0.1); Earth air (Rayleigh, the default aerosol, ozone), ground albedo 0.2; sun 35 deg above the horizon
in the south-east (zenith 55 deg, azimuth 135 deg). Views: the pixel centres inside the circle of an equidistant
fisheye looking up (``skyscatter.conventions.fisheye_directions``, ``--size`` pixels across), 450, 550 and 650 nm
on one path (hero wavelengths), ``--samples`` paths per pixel, Monte Carlo seed ``--seed``. The solar disc is not
in the Monte Carlo's radiance.

Usage: ``python benchmarks/broken_cloud_montecarlo.py [--size 32] [--samples 1024] [--seed 2201]`` writes
tests/data/broken_cloud_montecarlo.npz (every input above is stored in it with the result).
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
from skyscatter.atmosphere.clouds import CloudField, CloudLayer
from skyscatter.conventions import fisheye_directions
from skyscatter.montecarlo import sky_radiance

OUT = Path(__file__).parents[1] / "tests" / "data" / "broken_cloud_montecarlo.npz"
WAVELENGTHS = np.array([450.0, 550.0, 650.0])
COVERS = (0.3, 0.6, 0.9)
#: The scene, as stored with the result (tests rebuild the fields from it).
SCENE = {"base": 1000.0, "top": 2500.0, "optical_depth": 10.0, "size": 16000.0, "resolution": [64, 64, 16],
         "feature_size": 4000.0, "field_seed": 3, "effective_radius": 10e-6, "ground_albedo": 0.2,
         "sun_zenith_deg": 55.0, "sun_azimuth_deg": 135.0}


def field_for(cover: float, scene: dict = SCENE) -> CloudField:
    """The procedural field of a cover fraction in the stored scene."""
    drops = CloudLayer(0.0, 1.0, 1.0, effective_radius=scene["effective_radius"])  # its optics only
    return CloudField.procedural(cover=cover, base=scene["base"], top=scene["top"], particles=drops,
                                 optical_depth=scene["optical_depth"], size=scene["size"],
                                 resolution=tuple(scene["resolution"]), feature_size=scene["feature_size"],
                                 seed=scene["field_seed"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=32, help="fisheye width [px]")
    ap.add_argument("--samples", type=int, default=1024, help="paths per pixel")
    ap.add_argument("--seed", type=int, default=2201, help="Monte Carlo seed (cover i uses seed + i)")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()
    print(f"machine: {len(os.sched_getaffinity(0))} cores, load average {os.getloadavg()[0]:.1f}")
    air = AtmosphereParameters(ground_albedo=SCENE["ground_albedo"])
    dirs, inside = fisheye_directions(args.size)
    d = dirs[inside]
    out: dict = {"directions": d, "inside": inside, "wavelengths": WAVELENGTHS, "covers": np.array(COVERS)}
    meta = dict(SCENE, size_px=args.size, samples=args.samples, seeds=[args.seed + i for i in range(len(COVERS))],
                script="benchmarks/broken_cloud_montecarlo.py")
    for i, cover in enumerate(COVERS):
        field = field_for(cover)
        t0 = time.perf_counter()
        res = sky_radiance(air, d, WAVELENGTHS, sun_zenith=math.radians(SCENE["sun_zenith_deg"]),
                           sun_azimuth=math.radians(SCENE["sun_azimuth_deg"]), samples=args.samples,
                           seed=args.seed + i, clouds=field)
        secs = time.perf_counter() - t0
        out[f"radiance_{i}"] = res.radiance
        out[f"stderr_{i}"] = res.stderr
        meta[f"paths_{i}"] = int(res.samples)
        meta[f"seconds_{i}"] = round(secs, 1)
        print(f"cover {cover}: cloud fraction {field.cloud_fraction():.3f}, {res.samples} paths per pixel, "
              f"{res.mean_vertices:.1f} events per path, median relative stderr "
              f"{np.median(res.stderr / np.maximum(res.radiance, 1e-30)):.3f}, {secs:.0f} s "
              f"(load {os.getloadavg()[0]:.1f})", flush=True)
    out["meta"] = np.array(json.dumps(meta))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_suffix(".tmp.npz")
    np.savez_compressed(tmp, **out)
    os.replace(tmp, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
