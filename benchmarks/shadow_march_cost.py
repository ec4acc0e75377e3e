"""CPU cost of a twilight sky with the single scattering's shadow march (docs/accuracy.md, "Low sun"), against
another source tree in alternated rounds.

Each round runs, in a fresh process per tree, ``BrunetonSky.spectral_radiance`` of 10^5 random upper-hemisphere
directions with the sun 6 deg below the horizon and a 2048 x 1024 equirect ``sky_image`` with the sun 4 deg below
it (default cached tables; the observer on the ground is in the Earth's shadow, so every sky ray's single
scattering is marched), each the best and median of 3 calls in CPU time (``time.process_time``: all threads), after
one call that compiles. The load average is printed with each figure.

``python benchmarks/shadow_march_cost.py --baseline /work/main/src [--rounds 2]`` (this tree: the ``src`` next to
this file).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

CHILD = r'''
import math, os, time
import numpy as np
from skyscatter import BrunetonSky
from skyscatter.precomputed import cached_atmosphere
from skyscatter.render.sky_image import sky_image
atm = cached_atmosphere()
rng = np.random.default_rng(1)
u = rng.uniform(0.0, 1.0, 100000)
ph = rng.uniform(0.0, 2.0 * np.pi, 100000)
s = np.sqrt(1.0 - u * u)
d = np.stack([s * np.cos(ph), s * np.sin(ph), u], -1)
sky6 = BrunetonSky(math.radians(96.0), 0.0, precomputed=atm)
sky4 = BrunetonSky(math.radians(94.0), 0.0, precomputed=atm)
sky6.spectral_radiance(d[:100])
sky_image(sky4, projection="equirect", width=64)

def cpu(fn, n=3):
    ts = []
    for _ in range(n):
        t = time.process_time()
        fn()
        ts.append(time.process_time() - t)
    return min(ts), sorted(ts)[len(ts) // 2]

a = cpu(lambda: sky6.spectral_radiance(d))
b = cpu(lambda: sky_image(sky4, projection="equirect", width=2048))
print(f"spectral_radiance 1e5 at -6 deg: best {a[0]:.3f} median {a[1]:.3f} CPU-s | 2048x1024 map at -4 deg: best "
      f"{b[0]:.3f} median {b[1]:.3f} CPU-s | load {os.getloadavg()[0]:.1f}")
'''


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", required=True, help="the other tree's src folder")
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    trees = {"this": str(Path(__file__).resolve().parents[1] / "src"), "baseline": args.baseline}
    for k in range(args.rounds):
        for name, src in trees.items():
            env = dict(os.environ, PYTHONPATH=src)
            out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True, check=True)
            print(f"round {k + 1} {name:8s} {out.stdout.strip()}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
