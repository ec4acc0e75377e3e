"""Latency of the command line (issue 12): `skyscatter sky --projection fisheye --width 256` against the bare
`python -c "import numpy, scipy, numba"`, warm caches (one untimed run of each first), alternating runs.

Warm caches include Python's bytecode cache: the runs are made without ``PYTHONDONTWRITEBYTECODE`` (if the
environment sets it, every run would compile skyscatter's modules from source again, about 0.06 s here, while
numpy, scipy and numba come compiled from their wheels; an installed skyscatter has its .pyc files too).

    python benchmarks/bench_cli_latency.py [--runs 7]

Prints the median wall time of each and their ratio (target <= 2.5). Run with PYTHONPATH pointing at the
checkout's src/ to measure it rather than an installed copy.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

SKY = [sys.executable, "-m", "skyscatter", "sky", "--projection", "fisheye", "--width", "256"]
BARE = [sys.executable, "-c", "import numpy, scipy, numba"]


ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def wall(cmd: list[str], cwd: str) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=cwd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV)
    return time.perf_counter() - t0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--runs", type=int, default=7)
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        wall(SKY, tmp), wall(BARE, tmp)  # warm the numba cache and the OS file cache
        sky, bare = [], []
        for _ in range(args.runs):
            sky.append(wall(SKY, tmp))
            bare.append(wall(BARE, tmp))
    s, b = statistics.median(sky), statistics.median(bare)
    print(f"skyscatter sky --projection fisheye --width 256: median {s:.2f} s (min {min(sky):.2f})")
    print(f"python -c 'import numpy, scipy, numba':          median {b:.2f} s (min {min(bare):.2f})")
    print(f"ratio of medians {s / b:.2f} (target <= 2.5); ratio of minima {min(sky) / min(bare):.2f}")


if __name__ == "__main__":
    main()
