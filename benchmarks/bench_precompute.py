"""Benchmark of the precomputed atmosphere (Bruneton & Neyret 2008), printed as a small report.

1. JIT compilation of all kernels, from an empty numba cache (a temporary NUMBA_CACHE_DIR).
2. Precomputation with the default table sizes (256 x 64, 64 x 16, 32 x 128 x 32 x 8), orders (the default 8 and
   the tail; 6 until 2026-12-05) and wavelengths (16, 400-700 nm), then the 3-wavelength mode, compiled code (best
   of ``--repeat`` runs; wall and CPU time).
3. A 1024 x 768 sky-and-ground camera view from 1 km altitude looking 10 deg down, from the tables.
4. Radiance's genssky (shipped in pyradiance's ``bin/``), which also precomputes multiple-scattering tables
   (Bruneton's 2017 scheme, 20 wavelengths), timed from an empty data folder in the same run; the ratio of
   the two precompute times is reported.
5. Whole processes, alternated (``--rounds N``): ``PrecomputedAtmosphere.compute()`` (default), the same with
   ``tables="rgb"`` (3 wavelengths), each in a new Python process (imports, loading the compiled kernels from a warm
   numba cache, computing), and genssky, round after round; CPU time (user + system) and peak resident memory of
   each process from ``getrusage``, best and median, and the CPU ratio to genssky's in the same rounds. The load
   average is printed: on a shared machine compare the ratios, not the seconds.

Usage: ``python benchmarks/bench_precompute.py [--repeat N] [--spectral N] [--no-genssky] [--rounds N]
[--rounds-only] [--orders 6,8]``. Run on an otherwise idle machine: other processes on the two cores inflate every
figure.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _timed(fn):
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w0, time.process_time() - c0


def bench_genssky(threads: int) -> float | None:
    try:
        import pyradiance
    except ImportError:
        print("genssky: pyradiance not installed, skipped")
        return None
    root = Path(pyradiance.__file__).parent
    exe = root / "bin" / "genssky"
    if not exe.exists():
        print(f"genssky: {exe} not found, skipped")
        return None
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, RAYPATH=f".{os.pathsep}{root / 'lib'}")
        cmd = [str(exe), "6", "21", "12", "-a", "45", "-o", "0", "-m", "0", "-y", "2024", "-n", str(threads),
               "-f", "bench"]
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=tmp, env=env, capture_output=True, text=True)
        dt = time.perf_counter() - t0
        data = sorted(p.name for p in (Path(tmp) / "atmos_data").glob("*"))
        if proc.returncode != 0 or not data:
            print(f"genssky failed (status {proc.returncode}): {proc.stderr.strip()[:200]}")
            return None
    print(f"genssky precompute + one sky ({threads} threads): {dt:.1f} s wall; tables: {', '.join(data)}")
    return dt


_CHILD = """
import resource, sys
from skyscatter.precomputed import PrecomputedAtmosphere
kw = {"orders": int(sys.argv[2])} if len(sys.argv) > 2 else {}
PrecomputedAtmosphere.compute(progress=False, tables=(sys.argv[1] or None) if len(sys.argv) > 1 else None, **kw)
"""


def _process(cmd: list[str], **kw) -> tuple[float, float, float]:
    """Run ``cmd``; its wall time [s], CPU time [s] (user + system of the child) and peak RSS [MiB]."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True, **kw)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, after.ru_maxrss / 1024  # ru_maxrss of children: the largest so far [KiB]


def bench_processes(rounds: int, threads: int, orders: list[int] | None = None) -> None:
    """Section 5 of the module docstring; ``orders``: also the default tables with these numbers of orders (each
    a case of its own, alternated with the others)."""
    import statistics

    try:
        import pyradiance

        root = Path(pyradiance.__file__).parent
        exe = root / "bin" / "genssky"
        gen = exe.exists()
    except ImportError:
        gen = False
    cases = {"default (16 wavelengths)": [sys.executable, "-c", _CHILD],
             "rgb (3 wavelengths)": [sys.executable, "-c", _CHILD, "rgb"]}
    for n in orders or []:
        cases[f"default, {n} orders"] = [sys.executable, "-c", _CHILD, "", str(n)]
    got: dict[str, list[tuple[float, float]]] = {name: [] for name in [*cases, "genssky"]}
    # peak RSS per process needs a fresh child-rusage high-water mark: measure it once per case, first, in a
    # process of its own
    rss: dict[str, float] = {}
    for name, cmd in cases.items():
        rss[name] = _peak_rss(cmd)
    print(f"load average before the rounds: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    for _ in range(rounds):
        for name, cmd in cases.items():
            wall, cpu, _ = _process(cmd)
            got[name].append((wall, cpu))
        if gen:
            with tempfile.TemporaryDirectory() as tmp:
                env = dict(os.environ, RAYPATH=f".{os.pathsep}{root / 'lib'}")
                cmd = [str(exe), "6", "21", "12", "-a", "45", "-o", "0", "-m", "0", "-y", "2024", "-n",
                       str(threads), "-f", "bench"]
                wall, cpu, _ = _process(cmd, cwd=tmp, env=env)
                got["genssky"].append((wall, cpu))
    print(f"load average after the rounds: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    if gen:
        with tempfile.TemporaryDirectory() as tmp:
            rss["genssky"] = _peak_rss(cmd, cwd=tmp, env=env)
    for name, runs in got.items():
        if not runs:
            continue
        walls = [w for w, _ in runs]
        cpus = [c for _, c in runs]
        line = (f"{name:<26s} CPU best {min(cpus):5.1f} s, median {statistics.median(cpus):5.1f} s; wall best "
                f"{min(walls):5.1f} s, median {statistics.median(walls):5.1f} s")
        if name in rss:
            line += f"; peak RSS {rss[name]:.0f} MiB"
        print(line)
    if gen and got["genssky"]:
        for name in cases:
            ratios = [c / g for (_, c), (_, g) in zip(got[name], got["genssky"], strict=True)]
            print(f"CPU ratio {name} / genssky, per round: best {min(ratios):.3f}, median "
                  f"{statistics.median(ratios):.3f}")


def _peak_rss(cmd: list[str], **kw) -> float:
    """Peak resident memory [MiB] of ``cmd`` run in a process of its own (a child's ``ru_maxrss`` high-water mark
    is shared by all children of a process)."""
    code = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True, capture_output=True); "
            "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
    out = subprocess.run([sys.executable, "-c", code, *cmd], check=True, capture_output=True, text=True, **kw)
    return int(out.stdout.split()[-1]) / 1024


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2, help="precompute runs (best is reported)")
    ap.add_argument("--no-genssky", action="store_true", help="skip Radiance's genssky")
    ap.add_argument("--spectral", type=int, default=0, metavar="N",
                    help="also time the spectral mode with N wavelengths evenly spread over 380-760 nm")
    ap.add_argument("--rounds", type=int, default=3,
                    help="alternated whole-process rounds of section 5 (0: skip)")
    ap.add_argument("--rounds-only", action="store_true", help="only section 5")
    ap.add_argument("--orders", default="", metavar="N,M",
                    help="section 5 also with these numbers of scattering orders (e.g. 6,8: an A/B of the default)")
    args = ap.parse_args()
    orders = [int(n) for n in args.orders.split(",") if n]
    if args.rounds_only:
        from skyscatter.precomputed.parallel import n_threads

        bench_processes(max(1, args.rounds), n_threads(), orders)
        return 0

    numba_cache = tempfile.mkdtemp(prefix="skyscatter-numba-")
    os.environ["NUMBA_CACHE_DIR"] = numba_cache  # before numba is imported: cold JIT cache
    import numpy as np

    from skyscatter.precomputed import PrecomputedAtmosphere
    from skyscatter.precomputed.parallel import n_threads
    from skyscatter.render.bruneton import camera_view

    threads = n_threads()
    print(f"machine: {os.cpu_count()} CPUs, {threads} worker threads; python {sys.version.split()[0]}")
    tiny = dict(transmittance_mu=16, transmittance_r=4, irradiance_mu_s=4, irradiance_r=4, scattering_r=4,
                scattering_mu=8, scattering_mu_s=4, scattering_nu=2)
    small_atm, wall, _ = _timed(lambda: PrecomputedAtmosphere.compute(orders=2, sizes=tiny, progress=False))
    _, wall_r, _ = _timed(lambda: camera_view(small_atm, 0.5, 0.0, width=8, height=8))
    print(f"JIT compilation (cold cache, all kernels): {wall + wall_r:.1f} s "
          f"(precompute kernels {wall:.1f} s, rendering kernels and colour set-up {wall_r:.1f} s)")

    best = None
    for i in range(max(1, args.repeat)):
        atm, wall, cpu = _timed(lambda: PrecomputedAtmosphere.compute(progress=False))
        print(f"precompute run {i + 1}: {wall:.1f} s wall, {cpu:.1f} s CPU")
        if best is None or wall < best[1]:
            best = (atm, wall, cpu)
    atm, wall, cpu = best
    print(f"precompute, default sizes {atm.sizes.scattering_shape}, {atm.orders} orders + tail, the default "
          f"{atm.wavelengths.size} wavelengths: {wall:.1f} s wall (target <= 30 s), {cpu:.1f} s CPU")
    _, wall3, cpu3 = _timed(lambda: PrecomputedAtmosphere.compute(progress=False, tables="rgb"))
    print(f"precompute, 3-wavelength mode (wavelengths='rgb'): {wall3:.1f} s wall, {cpu3:.1f} s CPU")
    for name, t in atm.timings.items():
        print(f"    {name:<22s} {t:6.2f} s")

    if args.spectral:
        wl = np.linspace(380.0, 760.0, args.spectral)
        spec, w_s, c_s = _timed(lambda: PrecomputedAtmosphere.compute(wavelengths=wl, progress=False))
        print(f"precompute, spectral mode with {wl.size} wavelengths: {w_s:.1f} s wall, {c_s:.1f} s CPU")
        del spec

    times = []
    for _ in range(3):
        img, dt, _ = _timed(lambda: camera_view(atm, math.radians(60), math.radians(180), altitude=1000.0,
                                                heading=math.radians(180), pitch=math.radians(-10),
                                                fov=math.radians(90), width=1024, height=768, include_sun=False))
        times.append(dt)
    print(f"1024 x 768 sky-and-ground view (XYZ -> HDR sRGB included): {min(times):.3f} s (target < 0.5 s); "
          f"finite {bool(np.all(np.isfinite(img)))}")

    if not args.no_genssky:
        g = bench_genssky(threads)
        if g:
            print(f"ratio skyscatter / genssky precompute time: {wall / g:.2f}")
    shutil.rmtree(numba_cache, ignore_errors=True)
    del os.environ["NUMBA_CACHE_DIR"]  # the whole processes below load the compiled kernels from the usual cache
    if args.rounds:
        bench_processes(args.rounds, threads, orders)
    return 0


if __name__ == "__main__":
    sys.exit(main())
