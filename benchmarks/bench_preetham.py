"""Benchmark the Preetham sky (issue 2): spectral radiance throughput and a 2048 x 1024 sky image.

Run: python benchmarks/bench_preetham.py   (prints the figures; targets: image < 1 s)
"""

from __future__ import annotations

import math
import platform
import time

import numpy as np

from skyscatter import PreethamSky
from skyscatter.conventions import equirect_directions
from skyscatter.render import sky_image
from skyscatter.spectral import DEFAULT_WAVELENGTHS


def best_of(fn, repeats=5):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times), float(np.median(times))


def main() -> None:
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}")
    sky = PreethamSky(2.5, math.radians(55.0), math.radians(120.0))
    d = equirect_directions(1024, 512).reshape(-1, 3)
    d = d[d[:, 2] > 0]
    sky.spectral_radiance(d[:10], DEFAULT_WAVELENGTHS)  # warm caches (colour-science tables)
    best, med = best_of(lambda: sky.spectral_radiance(d, DEFAULT_WAVELENGTHS))
    print(f"PreethamSky.spectral_radiance, {d.shape[0]} directions x 41 wavelengths: best {best:.3f} s, "
          f"median {med:.3f} s -> {d.shape[0] / best / 1e6:.2f} M directions/s")
    best, med = best_of(lambda: sky.xyz(d))
    print(f"PreethamSky.xyz, {d.shape[0]} directions: best {best:.3f} s -> {d.shape[0] / best / 1e6:.1f} M dir/s")
    sky_image(sky, width=64)  # warm up photometry and sunlight tables
    best, med = best_of(lambda: sky_image(sky, width=2048), repeats=5)
    print(f"sky_image equirect 2048 x 1024 RGB (sun disc, ground): best {best:.3f} s, median {med:.3f} s "
          f"(target < 1 s)")
    best, med = best_of(lambda: sky_image(sky, projection="fisheye", width=1024), repeats=5)
    print(f"sky_image fisheye 1024 x 1024 RGB: best {best:.3f} s, median {med:.3f} s")


if __name__ == "__main__":
    main()
