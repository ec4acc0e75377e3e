"""Speed of the cloudy sky (``CloudySky``): the tables that light the cloud top, the DISORT solve per sky, and a
2048 x 1024 environment map of an overcast sky from a solved sky; CPU time (``time.process_time``, all threads)
and wall time, best and median of ``--repeat`` fresh skies (a new sun each), load average printed.

``python benchmarks/bench_cloudy.py [--repeat 5]``: the coupling tables are built in a fresh cache folder (so
their build is timed), then reused as they are in use; the numba kernels are compiled or loaded and the droplet
optics computed or read by a first sky before the rounds (a cold process's cost: docs/clouds.md, "Speed").
"""

from __future__ import annotations

import argparse
import math
import os
import statistics
import tempfile
import time
import warnings


def _stats(label: str, cpu: list[float], wall: list[float]) -> str:
    return (f"{label}: CPU best {min(cpu):.3f} s, median {statistics.median(cpu):.3f} s; "
            f"wall best {min(wall):.3f} s, median {statistics.median(wall):.3f} s")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as cache:
        os.environ["SKYSCATTER_CACHE_DIR"] = cache
        from skyscatter.render import sky_image
        from skyscatter.sky.cloudy import CloudySky

        sky = CloudySky(math.radians(50.0), math.radians(135.0), cloud_optical_depth=15.0)
        sky.luminance([[0.0, 0.0, 1.0]])  # numba kernels compiled or loaded
        print(f"load average {os.getloadavg()}")
        t0 = time.perf_counter()
        sky = CloudySky(math.radians(40.0), math.radians(135.0), cloud_optical_depth=15.0, ground_albedo=0.15)
        sky._field  # noqa: B018 (the tables for this air are built here: a new cache folder and albedo)
        sky_image(sky, width=2048)  # the map's kernels
        print(f"coupling tables (16 wavelengths, 16 x 64 x 32 x 4) + first solve and map: "
              f"{time.perf_counter() - t0:.2f} s")
        solve_cpu, solve_wall, map_cpu, map_wall = [], [], [], []
        for k in range(a.repeat):
            s = CloudySky(math.radians(41.0 + 7.0 * k), math.radians(135.0), cloud_optical_depth=15.0,
                          ground_albedo=0.15)
            c0, w0 = time.process_time(), time.perf_counter()
            s._field  # noqa: B018
            c1, w1 = time.process_time(), time.perf_counter()
            img = sky_image(s, width=2048)
            c2, w2 = time.process_time(), time.perf_counter()
            solve_cpu.append(c1 - c0)
            solve_wall.append(w1 - w0)
            map_cpu.append(c2 - c1)
            map_wall.append(w2 - w1)
        total_cpu = [x + y for x, y in zip(solve_cpu, map_cpu, strict=True)]
        total_wall = [x + y for x, y in zip(solve_wall, map_wall, strict=True)]
        print(_stats("solve per sky (17 wavelengths, 16 streams, about 105 x 45 directions)", solve_cpu, solve_wall))
        print(_stats(f"2048 x 1024 environment map {img.shape} from the solved sky", map_cpu, map_wall))
        print(_stats("solve + map (target <= 1 s)", total_cpu, total_wall))
        print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
