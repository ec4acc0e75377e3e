"""What the lookups' refined sun-zenith axis costs (docs/accuracy.md, "Low sun"; docs/bruneton.md).

The rendering lookups read the 4D tables refined along the sun zenith in the cells that start below the horizon
(``lookup.refine_sun_zenith``): the observer's path refines the two radius rows it reads, once per sky; the per-ray
paths (general sky, aerial perspective) read whole refined tables, built once per atmosphere on first use. This
script measures, on the default 16-wavelength tables (cached file), CPU time (``time.process_time``, all threads)
best of ``--repeat``:

* ``first_per_ray``: the first per-ray call (10 rays) after a sky seen by one observer, wall time, which builds the
  per-ray paths' refined tables, and the resident memory it adds (``/proc/self/statm``);
* ``observer``: ``sky_luminance`` for 10^6 upper-hemisphere directions from the ground at sun +50 and -3 deg, each
  call with its slices (so the rows' refinement is in every call);
* ``per-ray``: ``sky_radiance`` with a position per ray (the general kernel), 2 x 10^5 rays, sun +30 and -3 deg;
* ``aerial``: ``aerial_perspective`` to points 5-60 km away, 2 x 10^5 rays, sun -3 deg;
* ``suns``: ``sky_radiance_suns`` for 145 directions x 500 suns from +60 to -6 deg.

Run it with ``PYTHONPATH`` at two trees in alternation to compare them (the figures in docs/bruneton.md were taken
so; on a tree without the refined read the ``build`` line measures the float32 decode the per-ray paths use).
``python benchmarks/bench_twilight_read.py [--repeat 3]`` prints one JSON line.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
import timeit

import numpy as np

from skyscatter.precomputed import cached_atmosphere


def cpu(fn, repeat: int) -> float:
    """Best CPU time [s] (all threads) of ``repeat`` calls."""
    return min(timeit.repeat(fn, number=1, repeat=repeat, timer=time.process_time))


def resident_mib() -> float:
    """Resident memory of this process [MiB] (Linux)."""
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2.0 ** 20


def sun_at(elev_deg: float) -> np.ndarray:
    e = math.radians(elev_deg)
    return np.array([0.0, math.cos(e), math.sin(e)])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3, help="runs per figure, the best is kept")
    args = ap.parse_args()
    atm = cached_atmosphere(progress=False)
    rng = np.random.default_rng(1)
    n = 10 ** 6
    z = rng.uniform(0.0, 1.0, n)
    phi = rng.uniform(0.0, 2 * math.pi, n)
    s = np.sqrt(1 - z * z)
    dirs = np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)
    ground = np.array([0.0, 0.0, atm.parameters.bottom_radius + 1.0])
    out: dict[str, float | str] = {"load": os.getloadavg()[0]}
    sun = sun_at(10.0)
    atm.sky_luminance(ground, dirs[:10], sun)
    rss0 = resident_mib()
    t0 = time.perf_counter()
    atm.sky_radiance(np.broadcast_to(ground, (10, 3)), dirs[:10], sun)  # the per-ray path: its tables built
    out["first_per_ray_wall_s"] = time.perf_counter() - t0
    out["first_per_ray_rss_mib"] = resident_mib() - rss0
    for e in (50.0, -3.0):
        atm.sky_luminance(ground, dirs[:1000], sun_at(e))  # compiled
        out[f"observer_{e:+g}_s"] = cpu(lambda e=e: atm.sky_luminance(ground, dirs, sun_at(e)), args.repeat)
    m = 200_000
    pos = np.broadcast_to(ground, (m, 3))
    for e in (30.0, -3.0):
        atm.sky_radiance(pos[:100], dirs[:100], sun_at(e))
        out[f"per_ray_{e:+g}_s"] = cpu(lambda e=e: atm.sky_radiance(pos, dirs[:m], sun_at(e)), args.repeat)
    pts = ground + dirs[:m] * rng.uniform(5e3, 60e3, m)[:, None]
    atm.aerial_perspective(pos[:100], pts[:100], sun_at(-3.0))
    out["aerial_-3_s"] = cpu(lambda: atm.aerial_perspective(pos, pts, sun_at(-3.0)), args.repeat)
    el = np.radians(np.linspace(60.0, -6.0, 500))
    suns = np.stack([np.zeros_like(el), np.cos(el), np.sin(el)], axis=1)
    atm.sky_radiance_suns(ground, dirs[:145], suns[:3])
    out["suns_s"] = cpu(lambda: atm.sky_radiance_suns(ground, dirs[:145], suns), args.repeat)
    print(json.dumps({k: (round(v, 4) if isinstance(v, float) else v) for k, v in out.items()}))


if __name__ == "__main__":
    main()
