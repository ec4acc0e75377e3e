"""Spectral sky matrix and gensdaymtx against the Monte Carlo reference, side by side (issue 24, item 3).

A year of weather made by tests/weather_synth.py ``write_year_epw`` (SPECTRL2 clear days, broken and overcast
days). Hours are drawn (seed 7, sun zenith below 80 deg) from those our retrieval calls clear, broken (the
clear / overcast blend) and cloudy (overcast): ``--hours`` in all, split 40 / 30 / 30 %. The Monte Carlo
(``skyscatter.montecarlo.sky_radiance``) runs through the same air and clouds as ours: clear hours the family's
base medium with the hour's retrieved aerosol optical depth and albedo (not a node); overcast hours the cloud
table's air (its aerosol node, the base albedo) with the retrieved water layer (1000-1500 m, 10 um droplets,
``CloudLayer``); broken hours ``(1 - f) MC_clear + f MC_overcast`` with the retrieved cloud fraction f (our
blend is an independent-pixel approximation of the hour: the Monte Carlo checks its two parts, it cannot check
the approximation itself). At the Tregenza patch centres and 450, 550, 650 nm. Ours is the matrix itself
(``spectral_sky_matrix``, Tregenza, one cell per patch, 5 nm bands at those wavelengths, no gases, divided by
the day's eccentricity); gensdaymtx's the patch value of its ``-m 1`` matrix in the 20 nm bands holding those
wavelengths. Each is compared as reduced radiance (radiance over its own extraterrestrial irradiance), per patch
more than 5 deg from the sun (overcast: 10 deg, where our forward peak sits in the sun's patch). Prints per
hour and per kind the median and 95th-percentile relative difference and the Monte Carlo's standard error, and
writes docs/images/spectral_skymatrix_montecarlo.png.

Usage: ``python benchmarks/compare_spectral_skymatrix_montecarlo.py [--samples 1000] [--hours 20]``.
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
    ap.add_argument("--samples", type=int, default=1000)
    ap.add_argument("--hours", type=int, default=20)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    from skyscatter.atmosphere.clouds import CloudLayer
    from skyscatter.conventions import direction_from_angles
    from skyscatter.fit.spectral_matrix import band_edges, spectral_sky_matrix
    from skyscatter.fit.weather import BROKEN, CLEAR, CLOUDY, HOUR_STATUS, retrieve_hourly_atmosphere
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
    up = h.sun_zenith < np.radians(80)
    n_clear = int(round(0.4 * args.hours))
    n_broken = int(round(0.3 * args.hours))
    picks = []
    for kind, code, k in (("clear", CLEAR, n_clear), ("broken", BROKEN, n_broken),
                          ("overcast", CLOUDY, args.hours - n_clear - n_broken)):
        pool = np.flatnonzero((h.status == code) & up & ((code != CLOUDY) | ~(h.cloud_cover < 0.8)))
        picks += [(int(i), kind) for i in rng.choice(pool, size=min(k, pool.size), replace=False)]
    picks.sort()
    geom = patch_scheme("tregenza")
    dirs = geom.centre_directions
    wl = np.array([450.0, 550.0, 650.0])
    centres = [450.0 + d for d in (-5, 0, 5)] + [550.0 + d for d in (-5, 0, 5)] + [650.0 + d for d in (-5, 0, 5)]
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = spectral_sky_matrix(None, scheme=geom, samples=1, bands=centres, atmosphere=h, gases=False)
    print(f"our matrix (Tregenza, {len(centres)} bands, the whole year): {time.perf_counter() - t0:.1f} s")
    k_ours = [1, 4, 7]  # the 5 nm bands centred on 450, 550, 650 nm
    _, edges5 = band_edges(centres)
    from skyscatter.atmosphere.gas_absorption import broadband_solar_spectrum

    fw, fe = broadband_solar_spectrum()
    e0_ours = np.array([np.interp(np.linspace(edges5[b], edges5[b + 1], 21), fw, fe).mean() for b in k_ours])
    c20, edges20 = band_edges(20)
    b_wl = [int(np.argmin(np.abs(c20 - w))) for w in wl]
    try:
        gens = gensdaymtx_matrix(epw)
    except Exception as exc:  # noqa: BLE001 - the peer is optional
        print(f"gensdaymtx skipped: {exc}")
        gens = None
    band_e0 = np.array([fe[(fw >= edges20[b]) & (fw <= edges20[b + 1])].mean() for b in b_wl])
    rows = []
    t0 = time.perf_counter()
    table_air = h.cloud_table.atmosphere if h.cloud_table is not None else None

    def mc_run(params, i, seed_offset=0):
        return sky_radiance(params, dirs, wl, sun_zenith=float(h.sun_zenith[i]), sun_azimuth=float(h.sun_azimuth[i]),
                            samples=args.samples, seed=int(i) + seed_offset)

    for i, kind in picks:
        tau, ssa = float(h.aerosol_optical_depth[i]), float(h.single_scattering_albedo[i])
        sun = direction_from_angles(h.sun_zenith[i], h.sun_azimuth[i])
        clear_air = AXIS_SETTERS["aerosol_single_scattering_albedo"](
            AXIS_SETTERS["aerosol_optical_depth"](fam.base, tau), ssa)
        parts = []
        if kind in ("clear", "broken"):
            mc = mc_run(clear_air, i)
            parts.append((1.0 - (h.cloud_fraction[i] if kind == "broken" else 0.0), mc, clear_air))
        if kind in ("broken", "overcast"):
            cod = float(h.cloud_optical_depth[i])
            cloudy_air = table_air.replace(particles=(*table_air.particles,
                                                      CloudLayer(1000.0, 1500.0, cod, effective_radius=10e-6)))
            mc = mc_run(cloudy_air, i, 1_000_003)
            parts.append((h.cloud_fraction[i] if kind == "broken" else 1.0, mc, cloudy_air))
        r_mc = sum(w * m.radiance / air.solar_irradiance_at(wl) for w, m, air in parts)
        se_mc = np.sqrt(sum((w * m.stderr / air.solar_irradiance_at(wl)) ** 2 for w, m, air in parts))
        r_ours = ds["sky_radiance"].values[i][:, k_ours] / (e0_ours * h.eccentricity[i])
        away = (dirs @ sun) < np.cos(np.radians(10.0 if kind == "overcast" else 5.0))
        d_ours = (r_ours / r_mc - 1)[away].ravel()
        rel_err = float(np.median((se_mc / np.maximum(r_mc, 1e-30))[away]))
        line = (f"{kind:8s} hour {i:5d} sun zenith {np.degrees(h.sun_zenith[i]):5.1f} deg, AOD {tau:.3f}"
                + (f", cloud tau {h.cloud_optical_depth[i]:.1f}, f {h.cloud_fraction[i]:.2f}" if kind != "clear"
                   else f", albedo {ssa:.3f}")
                + f": ours vs MC median {np.median(d_ours) * 100:+.1f} %, |.| p95 "
                  f"{np.percentile(abs(d_ours), 95) * 100:.1f} %")
        shape = None
        if gens is not None:
            r_g = gens[i][:, b_wl] / (band_e0 * h.eccentricity[i])
            scale = np.median((r_g / r_mc)[away])
            shape = ((r_g / r_mc) / scale - 1)[away].ravel()
            line += (f"; gensdaymtx / MC median ratio {scale:.3g}, after that scale median "
                     f"{np.median(shape) * 100:+.1f} %, p95 {np.percentile(abs(shape), 95) * 100:.1f} %")
        line += f" (MC median standard error {rel_err * 100:.1f} %)"
        print(line, flush=True)
        rows.append((i, kind, d_ours, shape, rel_err))
    print(f"Monte Carlo time {time.perf_counter() - t0:.0f} s ({args.samples} paths per direction and run)")
    for kind in ("clear", "broken", "overcast", "all"):
        sel = [r for r in rows if kind in ("all", r[1])]
        if not sel:
            continue
        a = np.concatenate([r[2] for r in sel])
        se = [r[4] for r in sel]
        line = (f"{kind:8s} ({len(sel)} h), ours vs MC: median {np.median(a) * 100:+.2f} %, median |.| "
                f"{np.median(abs(a)) * 100:.2f} %, p95 |.| {np.percentile(abs(a), 95) * 100:.1f} % (MC standard "
                f"error {min(se) * 100:.1f}-{max(se) * 100:.1f} %)")
        if gens is not None:
            g = np.concatenate([r[3] for r in sel])
            line += (f"; gensdaymtx after each hour's median scale: median |.| {np.median(abs(g)) * 100:.2f} %, "
                     f"p95 |.| {np.percentile(abs(g), 95) * 100:.1f} %")
        print(line)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(10, 4))
        pos = np.arange(len(rows))
        ax.boxplot([r[2] * 100 for r in rows], positions=pos - 0.18, widths=0.3, showfliers=False,
                   patch_artist=True, boxprops={"facecolor": "tab:blue", "alpha": 0.6})
        if gens is not None:
            ax.boxplot([r[3] * 100 for r in rows], positions=pos + 0.18, widths=0.3, showfliers=False,
                       patch_artist=True, boxprops={"facecolor": "tab:orange", "alpha": 0.6})
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xticks(pos, [f"{r[0]} {r[1][0]}" for r in rows], rotation=60, fontsize=7)
        ax.set_xlabel("hour of the year (c clear, b broken, o overcast; 3 wavelengths x Tregenza patches away from "
                      "the sun)")
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
