"""Timing of sun position and sunlight (prints figures; run with the project's Python).

    python benchmarks/bench_sun.py
"""

from __future__ import annotations

import math
import time

import numpy as np
import pandas as pd

from skyscatter.spectral import DEFAULT_WAVELENGTHS
from skyscatter.sun import sun_position, sun_spectral_radiance


def best_of(fn, repeat: int = 5) -> float:
    """Best wall time [s] of ``repeat`` calls (after one warm-up call)."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    times = pd.date_range("2024-01-01", periods=8760, freq="h", tz="Europe/Paris")
    lat, lon = math.radians(48.85), math.radians(2.35)
    as_list = list(times.to_pydatetime())
    print(f"sun_position, {len(times)} hourly times (pandas DatetimeIndex):")
    for method in ("spa", "preetham1999"):
        t = best_of(lambda m=method: sun_position(lat, lon, times, method=m))
        print(f"  {method:13s} {t * 1e3:8.2f} ms  ({t / len(times) * 1e6:.2f} us per time)")
    print(f"sun_position, {len(as_list)} hourly times (list of aware datetimes):")
    for method in ("spa", "preetham1999"):
        t = best_of(lambda m=method: sun_position(lat, lon, as_list, method=m))
        print(f"  {method:13s} {t * 1e3:8.2f} ms")

    zenith = np.linspace(0.0, math.radians(89.0), 10_000)
    wl = DEFAULT_WAVELENGTHS
    t = best_of(lambda: sun_spectral_radiance(zenith, 3.0, wl))
    n = zenith.size * wl.size
    print(f"sun_spectral_radiance, {zenith.size} zeniths x {wl.size} wavelengths:")
    print(f"  {t * 1e3:8.2f} ms  ({t / n * 1e9:.1f} ns per value)")


if __name__ == "__main__":
    main()
