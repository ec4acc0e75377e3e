"""Spectral sky matrix of a year beside Radiance's gensdaymtx, in the same run (issue 24, item 5).

One site, 8760 hours (tests/weather_synth.py ``write_year_epw``: SPECTRL2 clear days, broken and overcast days),
20 bands 380-780 nm, Reinhart MF 2: ``skyscatter skymatrix --spectral`` as a process and Radiance's
``gensdaymtx -m 2`` (pyradiance) on the same file, alternated for ``--repeat`` rounds; wall time and peak RSS of
each process (``resource.getrusage`` of the finished child). The tables (ours: the 36-node family, 27 of them
used, gensdaymtx: its ``atmos_data``) are built once before the timed rounds and reported separately. Then the
multi-site Dask runner on 4 copies of the file with 1 and 2 threads (``--sites``).

Each process's CPU time (user + system of the finished child) is printed beside its wall time: on the shared
machine the CPU time is the comparable figure. ``--tables coarse`` runs the quick-look tables instead of the
default ones (what ``skyscatter skymatrix --spectral`` uses; their first build, the cold case, is the family line).

After the rounds it prints, per program, the best and the median over the rounds of the wall and CPU times and
of the peak RSS, and the per-round ratio ours / gensdaymtx (best and median), with the load average (1 min) at
the end of each round: ``--warmup`` runs each program once, untimed, before the rounds (the page cache then holds
the tables and the Python modules, so the first round is not the cold case).

Usage: ``python benchmarks/bench_spectral_skymatrix.py [--repeat 2] [--warmup] [--sites 4] [--skip-gensdaymtx]
[--tables default|coarse]``. Set SKYSCATTER_CACHE_DIR to a cache that holds (or may hold) the family. State the
load average with the numbers.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def run(cmd: list[str], env: dict, cwd: Path | None = None) -> tuple[float, float, float]:
    """(wall seconds, peak RSS MiB, CPU seconds) of a child process."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, env=env, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _, _, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    out, err = proc.communicate()
    if proc.returncode not in (0, None) and usage is None:
        raise RuntimeError(err.decode()[-400:])
    return wall, usage.ru_maxrss / 1024.0, usage.ru_utime + usage.ru_stime


def summary(stats: dict[str, list[tuple[float, float, float, float]]]) -> None:
    """Best and median over the rounds of each program's wall time, CPU time [s] and peak RSS [MiB], the range of
    the load average at the rounds' ends, and the per-round ratios ours / gensdaymtx."""
    import numpy as np

    for name, rows in stats.items():
        if not rows:
            continue
        a = np.array(rows)
        print(f"{name}: {len(rows)} rounds: wall best {a[:, 0].min():.1f} s, median {np.median(a[:, 0]):.1f} s; "
              f"CPU best {a[:, 1].min():.1f} s, median {np.median(a[:, 1]):.1f} s; peak RSS {a[:, 2].min():.0f}-"
              f"{a[:, 2].max():.0f} MiB (median {np.median(a[:, 2]):.0f}); "
              f"load {a[:, 3].min():.1f}-{a[:, 3].max():.1f}")
    if stats["ours"] and len(stats["gensdaymtx"]) == len(stats["ours"]):
        o, g = np.array(stats["ours"]), np.array(stats["gensdaymtx"])
        rw, rc = o[:, 0] / g[:, 0], o[:, 1] / g[:, 1]
        print(f"ratio ours / gensdaymtx per round: wall {np.round(rw, 2).tolist()} (best-to-best "
              f"{o[:, 0].min() / g[:, 0].min():.2f}, median {np.median(rw):.2f}); CPU {np.round(rc, 2).tolist()} "
              f"(best-to-best {o[:, 1].min() / g[:, 1].min():.2f}, median {np.median(rc):.2f})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--warmup", action="store_true", help="one untimed run of each program before the rounds")
    ap.add_argument("--sites", type=int, default=4)
    ap.add_argument("--skip-gensdaymtx", action="store_true")
    ap.add_argument("--tables", choices=("default", "coarse"), default="default")
    args = ap.parse_args()
    from weather_synth import write_year_epw

    work = Path(tempfile.mkdtemp(prefix="bench-spectral-"))
    epw = write_year_epw(work / "year.epw")
    env = dict(os.environ)
    print(f"load average before: {os.getloadavg()}")
    t0 = time.perf_counter()
    import warnings

    from skyscatter.fit.weather import RetrievalOptions, default_family

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        default_family(RetrievalOptions(tables=args.tables)).build(progress=False)
    print(f"family tables ready (built or loaded): {time.perf_counter() - t0:.1f} s")
    ours = [sys.executable, "-m", "skyscatter", "skymatrix", "--spectral", str(epw), "--patches", "reinhart2",
            "--out", str(work / "year.nc"), "--no-progress", "--tables", args.tables]
    rad_dir = Path(os.environ.get("SKYSCATTER_CACHE_DIR", work)) / "radiance"
    rad_dir.mkdir(parents=True, exist_ok=True)
    gens = None
    if not args.skip_gensdaymtx:
        import pyradiance

        root = Path(pyradiance.__file__).parent
        gens = [str(root / "bin" / "gensdaymtx"), "-m", "2", str(epw)]
        genv = dict(env, RAYPATH=f".{os.pathsep}{root / 'lib'}")
        t0 = time.perf_counter()
        subprocess.run(gens[:1] + ["-m", "1", str(epw)], cwd=rad_dir, env=genv, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL, check=False)
        print(f"gensdaymtx atmos_data ready (built or loaded, plus one Tregenza run): {time.perf_counter() - t0:.1f} s")
    if args.warmup:
        (work / "year.nc").unlink(missing_ok=True)
        w, m, c = run(ours, env)
        print(f"warm-up (untimed): skyscatter skymatrix --spectral: {w:.1f} s wall, {c:.1f} s CPU, peak {m:.0f} MiB "
              f"(load {os.getloadavg()[0]:.1f})")
        if gens is not None:
            with open(work / "g.mtx", "wb") as fh:
                subprocess.run(gens, cwd=rad_dir, env=genv, stdout=fh, stderr=subprocess.DEVNULL, check=False)
    stats: dict[str, list[tuple[float, float, float, float]]] = {"ours": [], "gensdaymtx": []}
    for r in range(args.repeat):
        (work / "year.nc").unlink(missing_ok=True)
        w, m, c = run(ours, env)
        stats["ours"].append((w, c, m, os.getloadavg()[0]))
        print(f"round {r + 1}: skyscatter skymatrix --spectral: {w:.1f} s wall, {c:.1f} s CPU, peak {m:.0f} MiB "
              f"(load {os.getloadavg()[0]:.1f})", flush=True)
        if gens is not None:
            with open(work / "g.mtx", "wb") as fh:
                t0 = time.perf_counter()
                p = subprocess.Popen(gens, cwd=rad_dir, env=genv, stdout=fh, stderr=subprocess.DEVNULL)
                _, _, usage = os.wait4(p.pid, 0)
                gw = time.perf_counter() - t0
            gc = usage.ru_utime + usage.ru_stime
            stats["gensdaymtx"].append((gw, gc, usage.ru_maxrss / 1024.0, os.getloadavg()[0]))
            print(f"round {r + 1}: gensdaymtx -m 2: {gw:.1f} s wall, {gc:.1f} s CPU, peak {usage.ru_maxrss / 1024:.0f} "
                  f"MiB (load {os.getloadavg()[0]:.1f}); ratio ours / gensdaymtx {w / gw:.2f} wall, {c / gc:.2f} CPU",
                  flush=True)
    summary(stats)
    if args.sites > 0:
        sites = []
        for k in range(args.sites):
            dst = work / f"site{k}.epw"
            shutil.copy(epw, dst)
            sites.append(str(dst))
        for workers in (1, 2):
            store = work / f"sites{workers}.zarr"
            cmd = [sys.executable, "-m", "skyscatter", "skymatrix", "--spectral", *sites, "--out", str(store),
                   "--workers", str(workers), "--no-progress", "--tables", args.tables]
            w, m, c = run(cmd, dict(env, SKYSCATTER_NUM_THREADS="1"))
            print(f"{args.sites} sites, Dask threads, {workers} worker(s), SKYSCATTER_NUM_THREADS=1: {w:.1f} s wall, "
                  f"{c:.1f} s CPU, peak {m:.0f} MiB (load {os.getloadavg()[0]:.1f})")
    print(f"load average after: {os.getloadavg()}")
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
