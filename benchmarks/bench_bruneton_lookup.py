"""Lookup speed of the precomputed sky (issue 11 item 4), side by side with Mitsuba 3's LLVM Hosek-Wilkie.

Measured in one run on the same 10^6 random upper-hemisphere directions (uniform in cos(zenith), the directions of
``bench_hosek_wilkie.py``), best of ``--repeat``:

* ``BrunetonSky.luminance`` / ``xyz`` on the default 16-wavelength tables (one observer: 2D table slices folded to
  XYZ), and on the whole sphere (ground rays add a spectral transmittance and irradiance term each);
* ``BrunetonSky.spectral_radiance`` at 41 wavelengths for 10^5 and 10^6 directions, with the peak memory of the
  call (tracemalloc: numpy allocations);
* a 2048 x 1024 environment map (``sky_image``, equirect, sun disc) and a 1024 x 768 camera view;
* Mitsuba's ``sunsky`` in ``llvm_ad_rgb`` (child process of ``bench_hosek_wilkie.py``; needs ``DRJIT_LIBLLVM_PATH``
  pointing at LLVM >= 16, see that file), numpy in and numpy out, and on device arrays, in ``--rounds`` rounds that
  alternate with ours (the machine's load changes from second to second: the ratio is taken per round).

Usage: ``python benchmarks/bench_bruneton_lookup.py [--repeat N] [--rounds N]``. The default tables are built
(about 15 s) if they are not cached.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np

from bench_hosek_wilkie import best_of, directions  # the same directions as the Hosek-Wilkie benchmark


def timed(fn, repeat):
    """Best wall time [s] of ``repeat`` calls."""
    return best_of(fn, repeat)[0]


def sphere(d: np.ndarray) -> np.ndarray:
    """The upper-hemisphere directions with every other one mirrored below the horizon."""
    out = d.copy()
    out[1::2, 2] *= -1.0
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="runs per figure (best is reported)")
    ap.add_argument("--rounds", type=int, default=3, help="alternating rounds of ours and Mitsuba's lookups")
    args = ap.parse_args()

    from skyscatter import BrunetonSky
    from skyscatter.precomputed import cached_atmosphere
    from skyscatter.render.bruneton import camera_view
    from skyscatter.render.sky_image import sky_image

    print(f"machine: {platform.machine()}, {os.cpu_count()} CPUs, python {platform.python_version()}, "
          f"load average {os.getloadavg()[0]:.1f}")
    atm = cached_atmosphere()
    sky = BrunetonSky(math.radians(50.0), math.radians(140.0), precomputed=atm)
    n = 1_000_000
    up = directions(n)
    whole = sphere(up)
    sky.xyz(up[:1000])
    for name, d, fn in (("BrunetonSky.luminance, upper hemisphere", up, sky.luminance),
                        ("BrunetonSky.xyz, upper hemisphere", up, sky.xyz),
                        ("BrunetonSky.xyz, whole sphere (half ground)", whole, sky.xyz)):
        t = timed(lambda fn=fn, d=d: fn(d), args.repeat)
        print(f"{name:48s} {n / t / 1e6:6.2f} M dir/s ({t * 1e9 / n:6.1f} ns/dir)")
    for m in (100_000, 1_000_000):
        d = up[:m]
        t = timed(lambda d=d: sky.spectral_radiance(d), max(1, args.repeat // 2))
        tracemalloc.start()
        sky.spectral_radiance(d)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        print(f"BrunetonSky.spectral_radiance, 41 wl, {m:>9d} dirs: {m / t / 1e6:6.2f} M dir/s, "
              f"peak {peak / 2**20:6.0f} MiB (output {m * 41 * 8 / 2**20:.0f} MiB)")
    t = timed(lambda: sky_image(sky, projection="equirect", width=2048), args.repeat)
    print(f"2048 x 1024 environment map (sky_image, equirect):  {t:.3f} s (target <= 1 s)")
    t = timed(lambda: camera_view(atm, math.radians(60), math.radians(180), altitude=1000.0,
                                    heading=math.radians(180), pitch=math.radians(-10), fov=math.radians(90),
                                    width=1024, height=768, include_sun=False), args.repeat)
    print(f"1024 x 768 sky-and-ground camera view:               {t:.3f} s (target < 0.5 s)")

    # Side by side: rounds alternate ours and Mitsuba's (a child process), so that both see the same load; each
    # round's ratio uses that round's best times.
    hw = Path(__file__).with_name("bench_hosek_wilkie.py")
    ratios = []
    for k in range(args.rounds):
        t = timed(lambda: sky.luminance(up), args.repeat)
        run = subprocess.run([sys.executable, str(hw), "llvm_ad_rgb", str(n)], capture_output=True, text=True)
        lines = [ln for ln in run.stdout.splitlines() if ln.startswith("mitsuba")]
        if run.returncode != 0 or not lines:
            print(f"mitsuba llvm_ad_rgb: not measured (exit {run.returncode}; set DRJIT_LIBLLVM_PATH, see {hw.name})")
            break
        rates = {("device" if "eval" in ln else "numpy"): float(ln.rsplit("->", 1)[1].split("M dir/s")[0])
                 for ln in lines}
        ours = n / t / 1e6
        ratios.append((ours / rates["numpy"], ours / rates["device"]))
        print(f"round {k + 1}: BrunetonSky.luminance {ours:6.2f} M dir/s; Mitsuba numpy in -> numpy out "
              f"{rates['numpy']:6.2f}, on device {rates['device']:6.2f} M dir/s; ours / Mitsuba {ratios[-1][0]:.2f} "
              f"(numpy in and out), {ratios[-1][1]:.2f} (device)")
    if ratios:
        a = np.array(ratios)
        print(f"ours / Mitsuba over {len(ratios)} rounds: numpy in and out {a[:, 0].min():.2f}-{a[:, 0].max():.2f} "
              f"(median {np.median(a[:, 0]):.2f}); on device {a[:, 1].min():.2f}-{a[:, 1].max():.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
