"""Speed of the ``broken-cloud`` sky: a 2048 x 1024 equirect map of a broken field (target <= 10 s on 2 cores).

Procedural field (cover 0.4, seed 1, base 1000 m, tops 2500 m, optical depth 10, 16 km periodic, 128 x 128 x 32
voxels), Earth air, sun 35 deg high in the south-east. Measured separately: the field's generation, the
per-sky set-up (shadow volume, vertical optical depths, the air's light at each layer), the map
(``sky_image``: the march, the clear sky's lookups, the solar disc). Best of ``--repeat`` runs after one warm-up
(compilation), the load average, and the peak resident memory of the process (``ru_maxrss``) and the peak of
numpy's allocations during one map (tracemalloc). Writes the map as EXR + PNG to ``--out`` (default
/tmp/broken_cloud_bench.exr). Usage: ``python benchmarks/bench_broken_cloud.py [--width 2048] [--repeat 3]``.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import time
import tracemalloc
from pathlib import Path

from skyscatter.render import sky_image, write_exr_and_png
from skyscatter.sky.broken_cloud import BrokenCloudSky


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=int, default=2048)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", type=Path, default=Path("/tmp/broken_cloud_bench.exr"))
    args = ap.parse_args()
    print(f"machine: {len(os.sched_getaffinity(0))} cores, load average {os.getloadavg()[0]:.1f}")
    zen, azi = math.radians(55.0), math.radians(135.0)
    BrokenCloudSky(zen, azi, cloud_cover=0.4, cloud_seed=1).xyz([[0.0, 0.0, 1.0]])  # warm-up: compile, tables
    best = {"field": math.inf, "setup": math.inf, "map": math.inf}
    image = None
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        sky = BrokenCloudSky(zen, azi, cloud_cover=0.4, cloud_seed=1)
        t1 = time.perf_counter()
        sky._volumes  # noqa: B018 - the per-sky set-up, timed on its own
        sky._light  # noqa: B018
        t2 = time.perf_counter()
        image = sky_image(sky, projection="equirect", width=args.width)
        t3 = time.perf_counter()
        for k, v in (("field", t1 - t0), ("setup", t2 - t1), ("map", t3 - t2)):
            best[k] = min(best[k], v)
        print(f"  field {t1 - t0:.2f} s, set-up {t2 - t1:.2f} s, map {t3 - t2:.2f} s "
              f"(load {os.getloadavg()[0]:.1f})", flush=True)
    tracemalloc.start()
    sky_image(sky, projection="equirect", width=args.width)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    total = best["field"] + best["setup"] + best["map"]
    print(f"best of {args.repeat}: field {best['field']:.2f} s, set-up {best['setup']:.2f} s, "
          f"{args.width} x {args.width // 2} map {best['map']:.2f} s; total {total:.2f} s")
    print(f"peak numpy allocations during one map {peak / 2**20:.0f} MiB; peak resident memory {rss:.0f} MiB")
    out, png = write_exr_and_png(args.out, args.out.with_suffix(".png"), image, key=0.45)
    print(f"wrote {out} and {png}")


if __name__ == "__main__":
    main()
