"""Speed of the cloudy sky (``CloudySky``): the tables that light the cloud top, the DISORT solve per sky, and a
2048 x 1024 environment map of an overcast sky from a solved sky (best of ``--repeat``; load average printed).

``python benchmarks/bench_cloudy.py [--repeat 3]``: the coupling tables are built in a fresh cache folder (so
their build is timed), then reused as they are in use.
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
import warnings


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
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
        print(f"coupling tables (16 wavelengths, 16 x 64 x 32 x 4) + first solve: {time.perf_counter() - t0:.2f} s")
        solves, maps = [], []
        for k in range(a.repeat):
            t0 = time.perf_counter()
            s = CloudySky(math.radians(40.0 + k), math.radians(135.0), cloud_optical_depth=15.0, ground_albedo=0.15)
            s._field  # noqa: B018
            solves.append(time.perf_counter() - t0)
        for _ in range(a.repeat):
            t0 = time.perf_counter()
            img = sky_image(s, width=2048)
            maps.append(time.perf_counter() - t0)
        print(f"solve per sky (17 wavelengths, 16 streams, about 105 x 45 directions): best {min(solves):.2f} s "
              f"(all {', '.join(f'{t:.2f}' for t in solves)})")
        print(f"2048 x 1024 environment map {img.shape}: best {min(maps):.2f} s "
              f"(all {', '.join(f'{t:.2f}' for t in maps)})")
        print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
