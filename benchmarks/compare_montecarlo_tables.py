"""Monte Carlo reference against the precomputed tables (Bruneton & Neyret 2008) per direction and sun elevation.

For the Earth defaults and a hazy atmosphere (``AtmosphereParameters.from_turbidity(3)``), at the table
wavelengths (440, 550, 680 nm), sun elevations +60 .. -6 deg and 15 view directions (elevations 2-90 deg at
azimuths 0, 90 and 180 deg from the sun), it prints a Markdown table of the relative difference
``tables / MC - 1`` and its Monte Carlo standard error, and draws ``docs/images/montecarlo_vs_tables.png``.
Tables: the default orders (``DEFAULT_ORDERS``: 6 until 2026-12-05, then 8; and the geometric tail) and sizes,
computed at exactly these three wavelengths (``tables="rgb"``: per-wavelength radiance, no colour rule involved;
cached on disk). Re-run after a change to the tables:
``python benchmarks/compare_montecarlo_tables.py [--samples N] [--out docs/images/montecarlo_vs_tables.png]
[--sizes scattering_nu=16,...]``.
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from skyscatter.montecarlo import sky_radiance
from skyscatter.precomputed import DEFAULT_ORDERS, AtmosphereParameters, cached_atmosphere

SUN_ELEVATIONS = [60.0, 30.0, 10.0, 3.0, 0.0, -3.0, -6.0]
VIEW_ELEVATIONS = [2.0, 10.0, 30.0, 60.0, 90.0]
REL_AZIMUTHS = [0.0, 90.0, 180.0]
WAVELENGTHS = np.array([440.0, 550.0, 680.0])


def directions() -> tuple[np.ndarray, list[tuple[float, float]]]:
    out, labels = [], []
    for az in REL_AZIMUTHS:
        for el in VIEW_ELEVATIONS:
            if el == 90.0 and az != 0.0:
                continue
            e, a = math.radians(el), math.radians(az)
            out.append([math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)])
            labels.append((el, az))
    return np.array(out), labels


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=65536, help="paths per direction with the sun above the horizon")
    ap.add_argument("--twilight-samples", type=int, default=262144,
                    help="paths per direction with the sun below the horizon (few paths reach the lit upper air)")
    ap.add_argument("--out", default="docs/images/montecarlo_vs_tables.png")
    ap.add_argument("--json", default=None, help="also write the numbers to this JSON file")
    ap.add_argument("--sizes", default="", help="table size overrides, e.g. scattering_nu=16,scattering_mu=64")
    args = ap.parse_args()
    sizes = {k: int(v) for k, v in (kv.split("=") for kv in args.sizes.split(",") if kv)} or None
    dirs, labels = directions()
    cases = {"Earth defaults": AtmosphereParameters(), "hazy (turbidity 3)": AtmosphereParameters.from_turbidity(3.0)}
    results = {}
    t0 = time.perf_counter()
    for name, params in cases.items():
        tables = cached_atmosphere(params, tables="rgb", sizes=sizes, progress=False)
        pos = np.array([0.0, 0.0, params.bottom_radius])
        for se in SUN_ELEVATIONS:
            zen = math.radians(90.0 - se)
            sun = np.array([0.0, math.sin(zen), math.cos(zen)])  # sun azimuth 0 (north)
            tab = tables.sky_radiance(pos, dirs, sun)  # (n, 3) at the table wavelengths (ascending)
            order = np.argsort(tables.wavelengths)
            tab = np.asarray(tab)[:, order]
            n = args.samples if se >= 0 else args.twilight_samples
            mc = sky_radiance(params, dirs, WAVELENGTHS, sun_zenith=zen, samples=n, seed=1)
            results[(name, se)] = (tab, mc.radiance, mc.stderr)
            print(f"# {name}, sun {se:+.0f} deg done ({time.perf_counter() - t0:.0f} s)", flush=True)

    # Markdown: per case and sun elevation, relative difference at 550 nm per direction, and summary
    print("\n| atmosphere | sun elev. [deg] | " + " | ".join(f"{el:.0f}/{az:.0f}" for el, az in labels)
          + " | median abs. (440/550/680) |")
    print("|---|---|" + "---|" * len(labels) + "---|")
    summary = {}
    for (name, se), (tab, mc, se_mc) in results.items():
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = tab / mc - 1
            rse = se_mc / mc
        cells = []
        for k in range(len(labels)):
            r, s = rel[k, 1], rse[k, 1]
            cells.append("-" if not np.isfinite(r) else f"{100 * r:+.1f}±{100 * s:.1f}")
        med = np.nanmedian(np.abs(rel), axis=0)
        summary[f"{name} {se:+.0f}"] = {"rel": rel.tolist(), "rel_stderr": rse.tolist(), "median_abs": med.tolist()}
        print(f"| {name} | {se:+.0f} | " + " | ".join(cells) + " | "
              + "/".join(f"{100 * m:.1f}" for m in med) + " % |")
    print("\ncolumns: view elevation / azimuth from the sun [deg]; cells: 100 (tables / MC - 1) ± 100 MC stderr / MC "
          "at 550 nm")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"labels": labels, "wavelengths": WAVELENGTHS.tolist(), "cases": summary}, fh, indent=1)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(13, 7), sharey="row", constrained_layout=True)
    colors = plt.cm.viridis(np.linspace(0, 0.9, len(SUN_ELEVATIONS)))
    for row, name in enumerate(cases):
        for col, az in enumerate(REL_AZIMUTHS):
            ax = axes[row, col]
            idx = sorted((k for k, (el, a) in enumerate(labels) if a == az or el == 90.0), key=lambda k: labels[k][0])
            els = [labels[k][0] for k in idx]
            for c, se in zip(colors, SUN_ELEVATIONS, strict=True):
                tab, mc, se_mc = results[(name, se)]
                with np.errstate(divide="ignore", invalid="ignore"):
                    rel = 100 * (tab[idx, 1] / mc[idx, 1] - 1)
                    err = 100 * se_mc[idx, 1] / mc[idx, 1]
                ax.errorbar(els, rel, yerr=2 * err, color=c, marker="o", ms=3, capsize=2, label=f"sun {se:+.0f}°")
            ax.axhline(0, color="k", lw=0.5)
            ax.set_ylim(-30, 80)
            ax.set_title(f"{name}, azimuth {az:.0f}° from the sun", fontsize=9)
            ax.set_xlabel("view elevation [deg]")
            if col == 0:
                ax.set_ylabel("tables / MC - 1 at 550 nm [%]")
    axes[0, 2].legend(fontsize=7, ncol=2)
    fig.suptitle(f"Precomputed tables ({DEFAULT_ORDERS} orders + tail, default sizes) vs Monte Carlo reference; "
                 "bars: 2 MC standard errors; "
                 "points beyond the axes are clipped")
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
