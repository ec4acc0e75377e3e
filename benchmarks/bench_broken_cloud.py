"""Speed of the ``broken-cloud`` sky: a 2048 x 1024 equirect map of a broken field (target <= 10 s on 2 cores).

Procedural field (cover 0.4, seed 1, base 1000 m, tops 2500 m, optical depth 10, 16 km periodic, 128 x 128 x 32
voxels), Earth air, sun 35 deg high in the south-east. Measured separately: the field's generation, the per-sky
set-up (shadow volume, vertical optical depths, the air's light at each layer), the map (``sky_image``: the march,
the clear sky's lookups, the solar disc). Best of ``--repeat`` runs after one warm-up (compilation), wall and CPU
time (``time.process_time``: the process's user + system time, all threads; on the shared machine CPU time is the
figure that does not move with the load), best and median, the load average, and the peak resident memory of the
process (``ru_maxrss``) and the peak of numpy's allocations during one map (tracemalloc). Writes the map as EXR +
PNG to ``--out`` (default /tmp/broken_cloud_bench.exr). Usage: ``python benchmarks/bench_broken_cloud.py [--width
2048] [--repeat 3]``.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import statistics
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
    stages = ("field", "setup", "map", "total")
    wall: dict[str, list[float]] = {k: [] for k in stages}
    cpu: dict[str, list[float]] = {k: [] for k in stages}
    image = None
    for _ in range(args.repeat):
        t = [(time.perf_counter(), time.process_time())]
        sky = BrokenCloudSky(zen, azi, cloud_cover=0.4, cloud_seed=1)
        t.append((time.perf_counter(), time.process_time()))
        sky._volumes  # noqa: B018 - the per-sky set-up, timed on its own
        sky._light  # noqa: B018
        t.append((time.perf_counter(), time.process_time()))
        image = sky_image(sky, projection="equirect", width=args.width)
        t.append((time.perf_counter(), time.process_time()))
        for i, k in enumerate(stages):
            a, b = (i, i + 1) if k != "total" else (0, 3)
            wall[k].append(t[b][0] - t[a][0])
            cpu[k].append(t[b][1] - t[a][1])
        print("  " + ", ".join(f"{k} {wall[k][-1]:.2f} s (CPU {cpu[k][-1]:.2f} s)" for k in stages)
              + f" (load {os.getloadavg()[0]:.1f})", flush=True)
    best = {k: min(v) for k, v in wall.items()}
    tracemalloc.start()
    sky_image(sky, projection="equirect", width=args.width)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    total = best["field"] + best["setup"] + best["map"]
    print(f"best of {args.repeat}: field {best['field']:.2f} s, set-up {best['setup']:.2f} s, "
          f"{args.width} x {args.width // 2} map {best['map']:.2f} s; total {total:.2f} s")
    for name, times in (("wall", wall), ("CPU", cpu)):
        print(f"{name} best / median of {args.repeat}: " + ", ".join(
            f"{k} {min(v):.2f} / {statistics.median(v):.2f} s" for k, v in times.items()))
    print(f"load average at the end {', '.join(f'{v:.2f}' for v in os.getloadavg())}")
    print(f"peak numpy allocations during one map {peak / 2**20:.0f} MiB; peak resident memory {rss:.0f} MiB")
    out, png = write_exr_and_png(args.out, args.out.with_suffix(".png"), image, key=0.45)
    print(f"wrote {out} and {png}")


if __name__ == "__main__":
    main()
