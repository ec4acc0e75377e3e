"""Benchmark of the Monte Carlo reference (skyscatter.montecarlo), printed as a small report.

1. Paths per second per core: one thread (synchronous scheduler), Earth defaults, sun elevation 20 deg, the
   11 wavelengths below sharing each path; CPU time of the process and wall time.
2. The reference of the issue: 1000 equal-area sky directions x 11 wavelengths, Earth defaults, sun elevation
   20 deg, with the paths per direction chosen from a pilot run so that the median relative standard error is
   <= 1 %; wall time on the threaded scheduler (all cores).
3. The same job on a dask.distributed LocalCluster with 2 worker processes (1 thread each) against the threaded
   scheduler, and a check that both give bit-identical radiances.
4. ``--overcast``: the same three under an overcast layer of optical depth 15 (Mie droplets r_e = 10 um,
   1000-1500 m; issue 21's job: 200 directions x 11 wavelengths, sun zenith 60 deg): paths per CPU-second and
   mean scattering events per path, the paths a 1 % median standard error needs (from a pilot) and the time that
   takes; the job is run at ``--overcast-samples`` paths (default: what the pilot asks, capped at 65536) threaded
   and on the LocalCluster, checked bit-identical.

Wavelengths: 11 from 360 to 760 nm (40 nm steps). The issue asks for 320-720 nm, but the ozone cross-sections
of the Earth defaults (Serdyuchenko et al. 2014) start at 360 nm and the medium refuses wavelengths outside its
spectra. Usage: ``python benchmarks/bench_montecarlo.py [--directions N] [--target 0.01] [--no-cluster]
[--overcast [--overcast-samples N] [--roulette-ab | --split-ab]]`` (``--roulette-ab``: the overcast pilot with and
without the shadow-ray roulette, alternating; ``--split-ab``: with and without the importance splitting,
``driver.SPLIT_FACTOR`` 1 / default, 4096 paths, 3 rounds, seeds 1-3). The clear-sky throughput against the
kernels before the clouds: ``benchmarks/bench_montecarlo_clear_ab.py``; with and without the binding of ``exp``
and ``log`` (``skyscatter.jit``): ``benchmarks/bench_libm_binding_ab.py``.
Run on an otherwise idle machine: other processes on the cores inflate every figure.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.montecarlo import sky_radiance
from skyscatter.montecarlo.dataset import almucantar_directions, equal_area_directions

WAVELENGTHS = np.arange(360.0, 761.0, 40.0)
SUN_ZENITH = math.radians(90.0 - 20.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--directions", type=int, default=1000)
    ap.add_argument("--target", type=float, default=0.01, help="median relative standard error")
    ap.add_argument("--no-cluster", action="store_true")
    ap.add_argument("--overcast", action="store_true", help="only the overcast section (4)")
    ap.add_argument("--overcast-samples", type=int, default=None)
    ap.add_argument("--layout", choices=("fibonacci", "almucantars"), default="fibonacci",
                    help="with --overcast: the 200 directions as the spherical Fibonacci set or 10 almucantars x 20 "
                         "azimuths (views of a ring share paths)")
    ap.add_argument("--roulette-ab", action="store_true",
                    help="with --overcast: only the pilot, with and without the shadow-ray roulette, alternating")
    ap.add_argument("--split-ab", action="store_true",
                    help="with --overcast: only the pilot, with and without the importance splitting, alternating")
    args = ap.parse_args()
    if args.overcast:
        overcast(args)
        return
    atm = AtmosphereParameters()
    dirs = equal_area_directions(args.directions)
    cores = len(os.sched_getaffinity(0))
    load = os.getloadavg()[0]
    print(f"machine: {cores} cores, load average {load:.1f} at start (shared machine: figures are lower bounds)")
    sky_radiance(atm, dirs[:2], WAVELENGTHS, sun_zenith=SUN_ZENITH, samples=8, scheduler="synchronous")  # compile

    # 1. paths per second per core
    sub = dirs[:: max(1, args.directions // 50)]
    c0 = time.process_time()
    pilot = sky_radiance(atm, sub, WAVELENGTHS, sun_zenith=SUN_ZENITH, samples=512, scheduler="synchronous", seed=1)
    cpu = time.process_time() - c0
    n_paths = sub.shape[0] * pilot.samples
    print(f"1. {n_paths} paths ({WAVELENGTHS.size} wavelengths each, {pilot.mean_vertices:.2f} scattering events per "
          f"path), one thread: {n_paths / cpu:,.0f} paths per CPU-second ({n_paths / pilot.seconds:,.0f} per "
          f"wall-second; wall {pilot.seconds:.1f} s, CPU {cpu:.1f} s)")
    med = float(np.median(pilot.relative_stderr))
    samples = int(math.ceil(pilot.samples * (med / args.target) ** 2 * 1.1 / 512) * 512)
    print(f"   pilot median relative stderr {med:.4f} at {pilot.samples} paths -> {samples} paths per direction "
          f"for {args.target:.2%}")

    # 2. the reference job, threaded
    res = sky_radiance(atm, dirs, WAVELENGTHS, sun_zenith=SUN_ZENITH, samples=samples, seed=7)
    rel = res.relative_stderr
    print(f"2. {dirs.shape[0]} directions x {WAVELENGTHS.size} wavelengths, {res.samples} paths each, threaded "
          f"scheduler: wall {res.seconds:.1f} s; median relative stderr {np.median(rel):.4f} (per wavelength "
          f"{', '.join(f'{w:.0f}:{m:.3f}' for w, m in zip(WAVELENGTHS, np.median(rel, 0), strict=True))}), "
          f"95th percentile {np.percentile(rel, 95):.4f}")

    # 3. LocalCluster with 2 worker processes
    if not args.no_cluster:
        from distributed import Client, LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                          silence_logs=50) as cluster, Client(cluster) as client:
            t0 = time.perf_counter()
            client.run(lambda: sky_radiance(atm, dirs[:1], WAVELENGTHS, sun_zenith=SUN_ZENITH, samples=8,
                                            scheduler="synchronous"))  # load the numba cache on the workers
            warm = time.perf_counter() - t0
            res2 = sky_radiance(atm, dirs, WAVELENGTHS, sun_zenith=SUN_ZENITH, samples=samples, seed=7,
                                scheduler=client)
        same = bool(np.array_equal(res2.radiance, res.radiance) and np.array_equal(res2.stderr, res.stderr))
        print(f"3. LocalCluster 2 processes x 1 thread: wall {res2.seconds:.1f} s (worker warm-up {warm:.1f} s) vs "
              f"threaded {res.seconds:.1f} s; bit-identical: {same}")
    print(f"load average at the end {os.getloadavg()[0]:.1f}")


def overcast(args) -> None:
    from skyscatter.atmosphere.clouds import CloudLayer

    atm = AtmosphereParameters(particles=(CloudLayer(1000.0, 1500.0, 15.0, effective_radius=10e-6),))
    # the 200 directions: the spherical Fibonacci set (no two of one zenith angle: every view traced alone) or
    # 10 almucantars x 20 azimuths (a sky scan's layout: the views of a ring share their paths, kernels docstring)
    dirs = almucantar_directions(10, 20) if args.layout == "almucantars" else equal_area_directions(200)
    sz = math.radians(60.0)
    print(f"machine: {len(os.sched_getaffinity(0))} cores, load average {os.getloadavg()[0]:.1f} at start")
    sky_radiance(atm, dirs[:1], WAVELENGTHS, sun_zenith=sz, samples=8, scheduler="synchronous")  # compile
    sub = dirs[::10] if args.layout == "fibonacci" else dirs  # 20 views alone, or the 10 rings whole
    if args.roulette_ab:
        roulette_ab(atm, sub, sz)
        return
    if args.split_ab:
        split_ab(atm, sub, sz)
        return
    c0 = time.process_time()
    pilot = sky_radiance(atm, sub, WAVELENGTHS, sun_zenith=sz, samples=1024 if args.layout == "fibonacci" else 512,
                         scheduler="synchronous", seed=1)
    cpu = time.process_time() - c0
    n_paths = sub.shape[0] * pilot.samples
    med = float(np.median(pilot.relative_stderr))
    need = pilot.samples * (med / 0.01) ** 2
    rate = n_paths / cpu
    sd = med * math.sqrt(pilot.samples)  # per-path relative standard deviation
    print(f"4. overcast tau 15 ({args.layout}): {rate:,.0f} paths per CPU-second on one thread, "
          f"{pilot.mean_vertices:.1f} scattering events per path ({rate * pilot.mean_vertices:,.0f} events per "
          f"CPU-second); pilot median relative stderr "
          f"{med:.3f} at {pilot.samples} paths (per-path relative standard deviation {sd:.2f}; efficiency "
          f"1 / (variance x CPU time per path) {rate / sd**2:,.0f}) -> "
          f"{need:,.0f} paths per direction for 1 %, "
          f"{200 * need / rate:,.0f} CPU-s = {200 * need / rate / 2 / 60:.0f} min on 2 cores")
    samples = args.overcast_samples or int(min(65536, math.ceil(need / 512) * 512))
    res = sky_radiance(atm, dirs, WAVELENGTHS, sun_zenith=sz, samples=samples, seed=7)
    print(f"   200 directions x {WAVELENGTHS.size} wavelengths, {res.samples} paths each, threaded: wall "
          f"{res.seconds:.1f} s, median relative stderr {np.median(res.relative_stderr):.4f}, "
          f"{res.mean_vertices:.1f} events per path")
    if not args.no_cluster:
        from distributed import Client, LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                          silence_logs=50) as cluster, Client(cluster) as client:
            client.run(lambda: sky_radiance(atm, dirs[:1], WAVELENGTHS, sun_zenith=sz, samples=8,
                                            scheduler="synchronous"))
            res2 = sky_radiance(atm, dirs, WAVELENGTHS, sun_zenith=sz, samples=samples, seed=7, scheduler=client)
        same = bool(np.array_equal(res2.radiance, res.radiance) and np.array_equal(res2.stderr, res.stderr))
        print(f"   LocalCluster 2 processes x 1 thread: wall {res2.seconds:.1f} s; bit-identical: {same}")
    print(f"load average at the end {os.getloadavg()[0]:.1f}")


def roulette_ab(atm, sub, sz, rounds=2) -> None:
    """The overcast pilot with the shadow-ray roulette off and on (``driver.NEE_ROULETTE_DEPTH`` inf / default),
    alternating ``rounds`` times in this process: paths per CPU-second, events per path, per-path relative standard
    deviation, efficiency 1 / (variance x CPU time) and the minutes a 1 % median standard error takes on 2 cores."""
    from skyscatter.montecarlo import driver

    default = driver.NEE_ROULETTE_DEPTH
    for _ in range(rounds):
        for depth in (math.inf, default):
            driver.NEE_ROULETTE_DEPTH = depth
            c0 = time.process_time()
            r = sky_radiance(atm, sub, WAVELENGTHS, sun_zenith=sz, samples=1024, scheduler="synchronous", seed=1)
            rate = sub.shape[0] * r.samples / (time.process_time() - c0)
            med = float(np.median(r.relative_stderr))
            sd = med * math.sqrt(r.samples)
            need = r.samples * (med / 0.01) ** 2
            print(f"   roulette depth {depth:g}: {rate:,.0f} paths per CPU-second, {r.mean_vertices:.1f} events per "
                  f"path, per-path relative std {sd:.2f}, efficiency {rate / sd**2:,.0f}; 1 %: {need:,.0f} paths per "
                  f"direction, {200 * need / rate / 2 / 60:.1f} min on 2 cores")
    driver.NEE_ROULETTE_DEPTH = default
    print(f"load average at the end {os.getloadavg()[0]:.1f}")


def split_ab(atm, sub, sz, rounds=3, samples=4096) -> None:
    """The overcast pilot without and with the importance splitting (``driver.SPLIT_FACTOR`` 1 / default),
    alternating ``rounds`` times in this process (seed 1 + round): the figures of :func:`roulette_ab`, and per round
    the z-scores of the two estimates' difference."""
    from skyscatter.montecarlo import driver

    default = driver.SPLIT_FACTOR
    for k in range(rounds):
        out = {}
        for factor in (1, default):
            driver.SPLIT_FACTOR = factor
            c0 = time.process_time()
            r = sky_radiance(atm, sub, WAVELENGTHS, sun_zenith=sz, samples=samples, scheduler="synchronous", seed=1 + k)
            rate = sub.shape[0] * r.samples / (time.process_time() - c0)
            sd = float(np.median(r.relative_stderr)) * math.sqrt(r.samples)
            need = r.samples * (sd / math.sqrt(r.samples) / 0.01) ** 2
            out[factor] = r
            print(f"   split factor {factor}: {rate:,.0f} paths per CPU-second, {r.mean_vertices:.1f} events per path, "
                  f"per-path relative std {sd:.2f}, efficiency {rate / sd**2:,.0f}; 1 %: {need:,.0f} paths per "
                  f"direction, {200 * need / rate / 2 / 60:.1f} min on 2 cores (load {os.getloadavg()[0]:.1f})")
        a, b = out[1], out[default]
        z = (b.radiance - a.radiance) / np.hypot(a.stderr, b.stderr)
        print(f"   round {k}: z split - plain: mean {z.mean():+.2f}, std {z.std():.2f}, "
              f"largest |z| {np.abs(z).max():.2f}")
    driver.SPLIT_FACTOR = default
    print(f"load average at the end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
