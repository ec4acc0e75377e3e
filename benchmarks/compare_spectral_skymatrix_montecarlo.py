"""Spectral sky matrix and gensdaymtx against the Monte Carlo reference, side by side (issue 24, item 3).

A year of weather made by tests/weather_synth.py ``write_year_epw`` (SPECTRL2 clear days, broken and overcast
days). 20 hours are drawn (seed 7) from the hours our retrieval calls clear (the broken and overcast hours have
no retrieved clouds yet, so there is no "same air and clouds" to give the Monte Carlo: listed, not compared).
For each hour the Monte Carlo (``skyscatter.montecarlo.sky_radiance``) runs through the medium of the retrieved
aerosol optical depth and albedo (the family's base atmosphere with the hour's values, not a node) at the
Tregenza patch centres and 450, 550, 650 nm; our value is the family's interpolated sky at the same directions
(the matrix's computation, without gases and eccentricity, which the Monte Carlo medium does not have) and
gensdaymtx's the patch value of its ``-m 1`` matrix in the bands holding those wavelengths. Each is compared as
reduced radiance (radiance over its own extraterrestrial irradiance: ours and the Monte Carlo's E0 at the
wavelength; gensdaymtx's band value over the ASTM band mean, with the day's eccentricity), per patch with the
sun more than 5 deg away. Prints the median and 95th-percentile relative difference per hour and overall, and
writes docs/images/spectral_skymatrix_montecarlo.png.

Usage: ``python benchmarks/compare_spectral_skymatrix_montecarlo.py [--samples 2000] [--hours 20]``
(about 10-20 CPU-minutes with the defaults).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def gensdaymtx_matrix(epw: Path) -> np.ndarray:
    """gensdaymtx -m 1 -fa: (hours, 145 patches, 20 bands, short to long)."""
    import pyradiance

    root = Path(pyradiance.__file__).parent
    cache = Path(os.environ.get("SKYSCATTER_CACHE_DIR", tempfile.gettempdir())) / "radiance"
    cache.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, RAYPATH=f".{os.pathsep}{root / 'lib'}")
    out = subprocess.run([str(root / "bin" / "gensdaymtx"), "-m", "1", str(epw)], cwd=cache, env=env,
                         capture_output=True, check=True).stdout
    head, body = out.split(b"\n\n", 1)
    text = head.decode()
    nrows = int(text.split("NROWS=")[1].split()[0])
    ncols = int(text.split("NCOLS=")[1].split()[0])
    ncomp = int(text.split("NCOMP=")[1].split()[0])
    vals = np.array(body.split(), dtype=float).reshape(nrows, ncols, ncomp)
    return vals[1:, :, ::-1].transpose(1, 0, 2)  # drop the ground row; components short to long


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=2000)
    ap.add_argument("--hours", type=int, default=20)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    from skyscatter.conventions import direction_from_angles
    from skyscatter.fit.spectral_matrix import band_edges
    from skyscatter.fit.weather import CLEAR, HOUR_STATUS, retrieve_hourly_atmosphere
    from skyscatter.montecarlo import sky_radiance
    from skyscatter.patches import patch_scheme
    from skyscatter.precomputed.family import AXIS_SETTERS
    from weather_synth import write_year_epw

    work = Path(tempfile.mkdtemp(prefix="mc-spectral-"))
    epw = write_year_epw(work / "year.epw")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h = retrieve_hourly_atmosphere(epw)
    fam = h.family
    counts = {HOUR_STATUS[k]: int((h.status == k).sum()) for k in HOUR_STATUS}
    print(f"retrieval: {counts}")
    rng = np.random.default_rng(args.seed)
    clear = np.flatnonzero((h.status == CLEAR) & (h.sun_zenith < np.radians(80)))
    hours = np.sort(rng.choice(clear, size=min(args.hours, clear.size), replace=False))
    geom = patch_scheme("tregenza")
    dirs = geom.centre_directions
    wl = np.array([450.0, 550.0, 650.0])
    k_wl = [list(fam.wavelengths).index(w) for w in wl]
    centres, edges = band_edges(20)
    b_wl = [int(np.argmin(np.abs(centres - w))) for w in wl]
    try:
        gens = gensdaymtx_matrix(epw)
    except Exception as exc:  # noqa: BLE001 - the peer is optional
        print(f"gensdaymtx skipped: {exc}")
        gens = None
    from skyscatter.atmosphere.gas_absorption import broadband_solar_spectrum

    fw, fe = broadband_solar_spectrum()
    band_e0 = np.array([fe[(fw >= edges[b]) & (fw <= edges[b + 1])].mean() for b in b_wl])
    rows = []
    ground = np.array([0.0, 0.0, fam.base.bottom_radius])
    t0 = time.perf_counter()
    for i in hours:
        tau, ssa = float(h.aerosol_optical_depth[i]), float(h.single_scattering_albedo[i])
        sun = direction_from_angles(h.sun_zenith[i], h.sun_azimuth[i])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ours = fam.interpolate([[tau, ssa]], lambda atm, sub, s=sun: atm.sky_radiance(ground, dirs, s)[None])[0]
        params = AXIS_SETTERS["aerosol_single_scattering_albedo"](
            AXIS_SETTERS["aerosol_optical_depth"](fam.base, tau), ssa)
        mc = sky_radiance(params, dirs, wl, sun_zenith=float(h.sun_zenith[i]), sun_azimuth=float(h.sun_azimuth[i]),
                          samples=args.samples, seed=int(i))
        e0 = params.solar_irradiance_at(wl)
        r_mc = mc.radiance / e0
        r_ours = ours[:, k_wl] / fam.base.solar_irradiance_at(fam.wavelengths)[k_wl]
        away = (dirs @ sun) < np.cos(np.radians(5.0))
        d_ours = (r_ours / r_mc - 1)[away].ravel()
        line = (f"hour {i:5d} sun zenith {np.degrees(h.sun_zenith[i]):5.1f} deg, AOD {tau:.3f}, albedo {ssa:.3f}: "
                f"ours vs MC median {np.median(d_ours) * 100:+.1f} %, "
                f"|.| p95 {np.percentile(abs(d_ours), 95) * 100:.1f} %")
        d_g = None
        if gens is not None:
            r_g = gens[i][:, b_wl] / (band_e0 * h.eccentricity[i])
            d_g = (r_g / r_mc - 1)[away].ravel()
            scale = np.median(r_g / r_mc)
            shape = ((r_g / r_mc) / scale - 1)[away].ravel()
            line += (f"; gensdaymtx / MC median ratio {np.median(d_g) + 1:.3g}, after that scale median "
                     f"{np.median(shape) * 100:+.1f} %, p95 {np.percentile(abs(shape), 95) * 100:.1f} %")
        rel_err = float(np.median((mc.stderr / np.maximum(mc.radiance, 1e-30))[away]))
        line += f" (MC median standard error {rel_err * 100:.1f} %)"
        print(line, flush=True)
        rows.append((i, d_ours, None if d_g is None else shape))
    print(f"Monte Carlo time {time.perf_counter() - t0:.0f} s")
    all_ours = np.concatenate([r[1] for r in rows])
    print(f"all hours, ours vs MC: median {np.median(all_ours) * 100:+.2f} %, median |.| "
          f"{np.median(abs(all_ours)) * 100:.2f} %, p95 |.| {np.percentile(abs(all_ours), 95) * 100:.1f} %")
    if gens is not None:
        all_g = np.concatenate([r[2] for r in rows])
        print(f"all hours, gensdaymtx vs MC after each hour's median scale: median {np.median(all_g) * 100:+.2f} %, "
              f"median |.| {np.median(abs(all_g)) * 100:.2f} %, p95 |.| {np.percentile(abs(all_g), 95) * 100:.1f} %")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(9, 4))
        pos = np.arange(len(rows))
        ax.boxplot([r[1] * 100 for r in rows], positions=pos - 0.18, widths=0.3, showfliers=False,
                   patch_artist=True, boxprops={"facecolor": "tab:blue", "alpha": 0.6})
        if gens is not None:
            ax.boxplot([r[2] * 100 for r in rows], positions=pos + 0.18, widths=0.3, showfliers=False,
                       patch_artist=True, boxprops={"facecolor": "tab:orange", "alpha": 0.6})
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xticks(pos, [str(r[0]) for r in rows], rotation=60, fontsize=7)
        ax.set_xlabel("hour of the year (clear hours; 3 wavelengths x Tregenza patches > 5 deg from the sun)")
        ax.set_ylabel("relative to Monte Carlo [%]")
        ax.set_title("patch radiance / Monte Carlo - 1: skyscatter (blue), gensdaymtx scaled by its median (orange)",
                     fontsize=9)
        fig.tight_layout()
        out = ROOT / "docs" / "images" / "spectral_skymatrix_montecarlo.png"
        fig.savefig(out, dpi=110)
        print(f"wrote {out}")
    except ImportError:
        pass
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
