"""Benchmark: a full-year (8760 h) Reinhart MF=2 (577 patches) Perez sky matrix, skyscatter vs Radiance gendaymtx.

Writes a synthetic but realistic EPW file (Munich-like site; pvlib Ineichen clear sky attenuated by a random
day-to-day cloudiness with hourly persistence), then times

* ``skyscatter.skymatrix(epw, scheme="reinhart2")`` (patch means over 3 x 3 cells, and patch centres), and
* ``gendaymtx -m 2 -s -O0 -of`` (pyradiance's binary, sky only, visible radiance) on the same EPW,

and compares the matrices: gendaymtx's visible radiance [W sr^-1 m^-2] times 179 lm/W (Radiance's white
efficacy; its output RGB carries the sky colour (0.96, 1.004, 1.118), whose Radiance luminance weight is 1)
against skyscatter's luminance [cd m^-2], patch by patch (gendaymtx's ground patch 0 dropped).

and, side by side (alternating runs, medians; issue 12's target is "faster than gendaymtx"):

* the API ``skyscatter.skymatrix(epw, scheme="reinhart2", samples=1)`` (patch centres, as gendaymtx) in this
  process, warm;
* the command line ``skyscatter skymatrix EPW --patches reinhart2 --samples 1 --out m.npz`` (a new process:
  imports, reading, computing and writing the file included), and
* ``gendaymtx -m 2 -s -O0 -of EPW > file`` (a new process, writing its binary matrix).

Warm caches include Python's bytecode cache: the command-line runs are made without ``PYTHONDONTWRITEBYTECODE``
(set, it makes every run compile skyscatter's modules from source again, about 0.06 s here; an installed
skyscatter has its .pyc files).

Run:  /work/venv/bin/python benchmarks/bench_skymatrix.py [--hours 8760] [--keep DIR] [--repeat 5]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

_EPW_HEADER = """LOCATION,Synthetic Munich,BY,DEU,skyscatter synthetic,108660,48.14,11.58,1.0,520.0
DESIGN CONDITIONS,0
TYPICAL/EXTREME PERIODS,0
GROUND TEMPERATURES,0
HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0
COMMENTS 1,Synthetic weather written by skyscatter benchmarks/bench_skymatrix.py (pvlib Ineichen + random clouds)
COMMENTS 2,Not measured data
DATA PERIODS,1,1,Data,Sunday, 1/ 1,12/31
"""


def write_synthetic_epw(path: Path, *, year: int = 2023, seed: int = 7, hours: int = 8760) -> Path:
    """Write an hourly EPW with physically plausible DNI/DHI (clear sky times a cloud factor)."""
    import pandas as pd
    import pvlib

    lat, lon, tz, elev = 48.14, 11.58, 1.0, 520.0
    end = pd.date_range(f"{year}-01-01 01:00", periods=hours, freq="h", tz=f"Etc/GMT-{int(tz)}")
    mid = end - pd.Timedelta(minutes=30)
    site = pvlib.location.Location(lat, lon, tz=f"Etc/GMT-{int(tz)}", altitude=elev)
    sp = site.get_solarposition(mid)
    cs = site.get_clearsky(mid, model="ineichen", solar_position=sp, linke_turbidity=3.0)
    rng = np.random.default_rng(seed)
    n_days = hours // 24 + 1
    day_cloud = np.clip(rng.beta(0.8, 0.8, n_days), 0.0, 1.0)  # mix of clear, broken and overcast days
    hourly = np.repeat(day_cloud, 24)[:hours]
    wiggle = np.convolve(rng.normal(0, 0.25, hours + 5), np.ones(6) / 6, mode="same")[:hours]
    cloud = np.clip(hourly + wiggle, 0.0, 1.0)
    dni = cs["dni"].to_numpy() * (1.0 - cloud) ** 1.5
    # diffuse rises with broken cloud, falls back towards a dim overcast level under thick cloud
    dhi = cs["dhi"].to_numpy() * (1.0 + 2.2 * cloud * (1.0 - cloud)) + cs["ghi"].to_numpy() * 0.25 * cloud**2
    cosz = np.cos(np.radians(sp["apparent_zenith"].to_numpy()))
    ghi = dhi + dni * np.clip(cosz, 0.0, None)
    doy = end.day_of_year.to_numpy()
    dry = 9.0 - 10.0 * np.cos(2 * np.pi * (doy - 20) / 365) + 4 * np.sin(2 * np.pi * (end.hour.to_numpy() - 9) / 24)
    dew = dry - 3.0 - 5.0 * (1.0 - cloud)
    lines = []
    for i, t in enumerate(end):
        hour = 24 if t.hour == 0 else t.hour
        day_t = t - pd.Timedelta(hours=1) if t.hour == 0 else t
        fields = [
            day_t.year, day_t.month, day_t.day, hour, 60, "?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9",
            f"{dry[i]:.1f}", f"{dew[i]:.1f}", 70, 95500, 9999, 9999, 9999,
            f"{ghi[i]:.0f}", f"{dni[i]:.0f}", f"{dhi[i]:.0f}", 999999, 999999, 999999, 9999,
            180, 2.0, 5, 5, 9999, 99999, 9, 999999999, 999, 0.999, 999, 99, 999, 999, 99,
        ]
        lines.append(",".join(str(f) for f in fields))
    path.write_text(_EPW_HEADER + "\n".join(lines) + "\n", encoding="utf-8")
    return path


def run_gendaymtx(epw: Path, mf: int) -> tuple[np.ndarray, float]:
    """gendaymtx -m MF -s -O0 -of on the EPW; returns (hours, patches+1, 3) visible radiance and the wall time."""
    import pyradiance

    exe = Path(pyradiance.BINPATH) / "gendaymtx"
    t0 = time.perf_counter()
    res = subprocess.run([str(exe), "-m", str(mf), "-s", "-O0", "-of", str(epw)], capture_output=True, check=True)
    elapsed = time.perf_counter() - t0
    raw = res.stdout
    header_end = raw.index(b"\n\n") + 2
    header = raw[:header_end].decode("ascii", "replace")
    ncols = int(next(line.split("=")[1] for line in header.splitlines() if line.startswith("NCOLS")))
    nrows = int(next(line.split("=")[1] for line in header.splitlines() if line.startswith("NROWS")))
    data = np.frombuffer(raw[header_end:], dtype="<f4").reshape(nrows, ncols, 3)
    return np.transpose(data, (1, 0, 2)), elapsed


def side_by_side(epw: Path, work: Path, repeat: int) -> None:
    """Alternate API, CLI and gendaymtx runs; print medians and the ratios to gendaymtx."""
    import pyradiance

    import skyscatter

    exe = Path(pyradiance.BINPATH) / "gendaymtx"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    cli = [sys.executable, "-m", "skyscatter", "skymatrix", str(epw), "--patches", "reinhart2", "--samples", "1",
           "--out", str(work / "cli.npz"), "--no-progress"]
    subprocess.run(cli, check=True, capture_output=True, env=env)  # warm caches
    t_api, t_cli, t_gen = [], [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        skyscatter.skymatrix(epw, scheme="reinhart2", samples=1)
        t_api.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        subprocess.run(cli, check=True, capture_output=True, env=env)
        t_cli.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        with open(work / "gendaymtx.bin", "wb") as fh:
            subprocess.run([str(exe), "-m", "2", "-s", "-O0", "-of", str(epw)], stdout=fh, check=True)
        t_gen.append(time.perf_counter() - t0)
    api, cli_t, gen = (statistics.median(x) for x in (t_api, t_cli, t_gen))
    b_api, b_cli, b_gen = (min(x) for x in (t_api, t_cli, t_gen))
    print(f"side by side, {repeat} alternating runs (medians, best in brackets; patch centres, reinhart2):")
    print(f"  API  skyscatter.skymatrix(samples=1)          : {api:6.2f} s ({b_api:.2f})  ratio to gendaymtx "
          f"{api / gen:.2f} ({b_api / b_gen:.2f})")
    print(f"  CLI  skyscatter skymatrix --samples 1 --out   : {cli_t:6.2f} s ({b_cli:.2f})  ratio to gendaymtx "
          f"{cli_t / gen:.2f} ({b_cli / b_gen:.2f})")
    print(f"  gendaymtx -m 2 -s -O0 -of > file             : {gen:6.2f} s ({b_gen:.2f})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=int, default=8760)
    ap.add_argument("--keep", type=Path, default=None, help="folder to keep the EPW and matrices in")
    ap.add_argument("--repeat", type=int, default=5, help="alternating runs of the side-by-side timing")
    args = ap.parse_args()
    import skyscatter
    from skyscatter.patches import patch_scheme

    work = Path(tempfile.mkdtemp(prefix="bench_skymatrix_"))
    try:
        epw = write_synthetic_epw(work / "synthetic.epw", hours=args.hours)
        skyscatter.skymatrix(epw, scheme="tregenza", chunk_hours=64)  # compile (or load) the numba kernel once
        timings = {}
        for samples in (3, 1):
            t0 = time.perf_counter()
            m = skyscatter.skymatrix(epw, scheme="reinhart2", samples=samples)
            timings[samples] = (time.perf_counter() - t0, m)
        t0 = time.perf_counter()
        timings[3][1].save_npz(work / "matrix.npz")
        t_npz = time.perf_counter() - t0
        t0 = time.perf_counter()
        timings[3][1].save_csv(work / "matrix.csv")
        t_csv = time.perf_counter() - t0
        ours, t_ours = timings[3][1], timings[3][0]
        centre, t_centre = timings[1][1], timings[1][0]

        rad = None
        try:
            rad, t_rad = run_gendaymtx(epw, 2)
        except (ImportError, FileNotFoundError, subprocess.CalledProcessError) as exc:
            print(f"gendaymtx unavailable: {exc}")
        lit = int(np.count_nonzero(ours.diffuse_illuminance > 0))
        print(f"hours {len(ours.times)} (with diffuse light: {lit}), patches {ours.shape[1]}")
        print(f"skyscatter skymatrix reinhart2, 3x3 cells/patch : {t_ours:6.2f} s")
        print(f"skyscatter skymatrix reinhart2, patch centres   : {t_centre:6.2f} s")
        print(f"  save_npz                                      : {t_npz:6.2f} s")
        print(f"  save_csv                                      : {t_csv:6.2f} s")
        for label, mat in (("3x3 means", ours), ("centres", centre)):
            lit_h = mat.diffuse_illuminance > 0
            err = mat.horizontal_illuminance()[lit_h] / mat.diffuse_illuminance[lit_h] - 1
            print(f"  patch sum L*Omega*sin(alt) vs D_v ({label}): median {100 * np.median(err):+.3f} %, "
                  f"max |.| {100 * np.max(np.abs(err)):.3f} %")
        if rad is None:
            return
        side_by_side(epw, work, args.repeat)
        print(f"gendaymtx -m 2 -s                               : {t_rad:6.2f} s")
        print(f"time ratio skyscatter/gendaymtx                 : {t_ours / t_rad:6.2f} "
              f"(centres {t_centre / t_rad:.2f})")
        geom = patch_scheme("reinhart2")
        rad_lum = 179.0 * (0.2651 * rad[..., 0] + 0.6701 * rad[..., 1] + 0.0648 * rad[..., 2])[:, 1:]
        if rad_lum.shape != ours.luminance.shape:
            print(f"shape mismatch: gendaymtx {rad_lum.shape}, skyscatter {ours.luminance.shape}")
            return
        w = geom.solid_angles * np.sin(geom.centre_altitude)
        for label, mat in (("3x3 means", ours.luminance), ("centres", centre.luminance)):
            both = (rad_lum.sum(axis=1) > 0) & (mat.sum(axis=1) > 0)
            a, b = mat[both], rad_lum[both]
            rel_hour = (a @ w) / (b @ w) - 1.0
            total = a.sum() / b.sum() - 1.0
            big = b > 0.05 * b.max(axis=1, keepdims=True)
            rel = np.abs(a[big] / b[big] - 1.0)
            only_ours = int(((mat.sum(1) > 0) & ~both).sum())
            only_rad = int(((rad_lum.sum(1) > 0) & ~both).sum())
            print(f"agreement ({label}): hours compared {both.sum()}, only-ours {only_ours}, only-gendaymtx {only_rad}")
            print(f"  annual sum of luminance        : {100 * total:+.2f} %")
            print(f"  hourly horizontal illuminance  : median {100 * np.median(rel_hour):+.2f} %, "
                  f"5-95 % [{100 * np.percentile(rel_hour, 5):+.2f}, {100 * np.percentile(rel_hour, 95):+.2f}] %")
            print(f"  patch values (> 5 % of hour max): median |diff| {100 * np.median(rel):.2f} %, "
                  f"95th pct {100 * np.percentile(rel, 95):.2f} %")
            corr = np.corrcoef(a.ravel(), b.ravel())[0, 1]
            print(f"  correlation of all values      : {corr:.5f}")
        if args.keep:
            args.keep.mkdir(parents=True, exist_ok=True)
            for f in work.iterdir():
                shutil.copy(f, args.keep / f.name)
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
