"""Where a Monte Carlo path's time goes, by compiled function: ``perf`` sampling of the overcast pilot with the
numba functions named.

perf sees numba's machine code as anonymous JIT memory (llvmlite is built without perf's JIT listener), so this
script compiles the kernels afresh (a temporary ``NUMBA_CACHE_DIR``: a kernel loaded from the cache has no LLVM
module to read), runs the pilot of ``bench_montecarlo.py --overcast`` (issue 21's layer of optical depth 15, Mie
droplets r_e 10 um at 1000-1500 m, sun zenith 60 deg, 20 of the 200 views, 11 wavelengths 360-760 nm, one
thread), and writes ``/tmp/perf-PID.map`` (removed after the report): start, size and name of every function in
``trace_block``'s compiled library (the helpers LLVM did not inline into their callers), which ``perf report``
reads. It then prints each function's share of the samples in the compiled code and libm (self time: an inlined
helper counts in its caller).
Usage: ``python benchmarks/profile_montecarlo_stages.py [--samples N] [--layout almucantars]`` (needs ``perf``;
re-runs itself under ``perf record``; ``--layout almucantars``: 2 rings of 20 views, each ring traced as one); run
from the repository with the tree under test first on PYTHONPATH.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from collections import defaultdict


def _run(samples: int, layout: str) -> None:
    import numpy as np

    from skyscatter.atmosphere import AtmosphereParameters
    from skyscatter.atmosphere.clouds import CloudLayer
    from skyscatter.montecarlo import kernels, sky_radiance
    from skyscatter.montecarlo.dataset import almucantar_directions, equal_area_directions

    wl = np.arange(360.0, 761.0, 40.0)
    atm = AtmosphereParameters(particles=(CloudLayer(1000.0, 1500.0, 15.0, effective_radius=10e-6),))
    # 20 of the 200 Fibonacci views (each traced alone), or 2 almucantars of 20 views (each traced as one)
    dirs = equal_area_directions(200)[::10] if layout == "fibonacci" else almucantar_directions(10, 20)[40:80]
    sz = math.radians(60.0)
    sky_radiance(atm, dirs[:2], wl, sun_zenith=sz, samples=8, scheduler="synchronous")  # compile
    c0 = time.process_time()
    r = sky_radiance(atm, dirs, wl, sun_zenith=sz, samples=samples, scheduler="synchronous", seed=1)
    cpu = time.process_time() - c0
    print(f"{dirs.shape[0] * r.samples / cpu:,.0f} paths per CPU-second, {r.mean_vertices:.1f} events per path "
          f"(CPU {cpu:.1f} s, load {os.getloadavg()[0]:.1f})", flush=True)
    syms = []
    for cres in kernels.trace_block.overloads.values():
        lib = cres.library
        for fn in lib._final_module.functions:
            if not fn.is_declaration:
                addr = lib.get_pointer_to_function(fn.name)
                if addr:
                    syms.append((addr, fn.name))
    syms.sort()
    path = f"/tmp/perf-{os.getpid()}.map"
    with open(os.path.join(os.path.dirname(os.environ["NUMBA_CACHE_DIR"]), "map"), "w") as fh:
        fh.write(path)
    with open(path, "w") as fh:
        for i, (addr, name) in enumerate(syms):
            size = syms[i + 1][0] - addr if i + 1 < len(syms) else 0x10000
            fh.write(f"{addr:x} {size:x} {name}\n")


def _short(sym: str) -> str:
    m = re.search(r"(kernels|_phase_numba|tracking|rng)\d+(\w+?)B\d", sym)
    return m.group(2) if m else sym


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=4096)
    ap.add_argument("--layout", choices=("fibonacci", "almucantars"), default="fibonacci")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        _run(args.samples, args.layout)
        return
    with tempfile.TemporaryDirectory() as tmp:
        data = os.path.join(tmp, "perf.data")
        env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(tmp, "numba"))
        subprocess.run(["perf", "record", "-q", "-F", "499", "-o", data, sys.executable, __file__, "--child",
                        "--samples", str(args.samples), "--layout", args.layout], env=env, check=True)
        rep = subprocess.run(["perf", "report", "-i", data, "--no-children", "--sort", "dso,sym", "--stdio"],
                             capture_output=True, text=True, check=True).stdout
        with open(os.path.join(tmp, "map")) as fh:
            os.remove(fh.read())  # the child's symbol map, read by perf report
    share: dict[str, float] = defaultdict(float)
    for line in rep.splitlines():
        m = re.match(r"\s*([\d.]+)%\s+(\[JIT\] tid \d+|libm\S*)\s+\[\.\]\s+(\S+)", line)
        if m:
            share[_short(m.group(3))] += float(m.group(1))
    total = sum(share.values())
    print(f"self time in the compiled code and libm ({total:.1f} % of the process's samples; the rest is "
          "compilation and Python):")
    for name, v in sorted(share.items(), key=lambda kv: -kv[1]):
        if v / total >= 0.003:
            print(f"  {100 * v / total:5.1f} %  {name}")


if __name__ == "__main__":
    main()
