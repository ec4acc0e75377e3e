"""ASRC-CIE against Perez 1993: the same hours of weather, the same sky condition, patch by patch (issue 26).

Both models take an hour's direct normal and diffuse horizontal irradiance through the same Perez et al. 1990
sky condition (epsilon, delta, luminous efficacies, dew point) and integrate to the same diffuse illuminance;
they differ only in how the light is spread over the sky. For every lit hour this script computes the sky
matrix of both (``skyscatter.skymatrix(..., model=...)``, Reinhart MF 2, 577 patches, 3 x 3 cells per patch)
and reports, per Perez sky-clearness bin and over the year:

* ``rms_rel``: the hour's RMS patch luminance difference divided by its mean patch luminance (Perez), i.e.
  ``sqrt(mean_p (L_asrc - L_perez)^2) / mean_p L_perez``; median and 90th percentile over the hours;
* ``pooled``: ``sqrt(sum (dL)^2 / sum L_perez^2)`` over all hours and patches of the bin (dominated by bright
  hours);
* ``zenith``: median ratio of the zenith patch (ASRC / Perez); ``circumsolar``: median ratio of the brightest
  Perez patch; ``horizon``: median ratio of the mean of the lowest band.

Weather: pvlib's TMY3 file for Greensboro, NC (``pvlib/data/723170TYA.CSV``, NREL TMY3, public domain), written
as an EPW in a temporary folder (year set to 1999 for every record), and the synthetic Munich-like year of
``bench_skymatrix.py``.

``--figure PATH`` also draws, for five sky conditions from overcast to clear (sun at 35 deg altitude, the same
diffuse illuminance), the luminance of both skies over the hemisphere (equal-area fisheye, log scale) and along
the solar meridian.

Run:  python benchmarks/compare_asrc_perez.py [--synthetic] [--markdown] [--figure docs/images/asrc_cie_vs_perez.png]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

EPW_HEADER = """LOCATION,{name},{state},USA,TMY3 via pvlib,{usaf},{lat:.3f},{lon:.3f},{tz:.1f},{alt:.1f}
DESIGN CONDITIONS,0
TYPICAL/EXTREME PERIODS,0
GROUND TEMPERATURES,0
HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0
COMMENTS 1,NREL TMY3 {usaf} (pvlib data/723170TYA.CSV) written as EPW by skyscatter benchmarks/compare_asrc_perez.py
COMMENTS 2,year set to 1999 for every record
DATA PERIODS,1,1,Data,Friday, 1/ 1,12/31
"""


def tmy3_as_epw(folder: Path) -> Path:
    """pvlib's Greensboro TMY3 year as an hourly EPW (the fields skyscatter reads; the rest missing codes)."""
    import pvlib

    data, meta = pvlib.iotools.read_tmy3(Path(pvlib.__file__).parent / "data" / "723170TYA.CSV",
                                         map_variables=True)
    head = EPW_HEADER.format(name=meta["Name"].strip('"'), state=meta["State"], usaf=meta["USAF"],
                             lat=meta["latitude"], lon=meta["longitude"], tz=meta["TZ"], alt=meta["altitude"])
    lines = []
    # the file's own date and hour-ending 1-24 (as EPW), not pandas' time stamps (24:00 moved to the next day)
    stamps = zip(data["Date (MM/DD/YYYY)"], data["Time (HH:MM)"], strict=True)
    for (date, clock), row in zip(stamps, data.itertuples(index=False), strict=True):
        month, day = (int(v) for v in date.split("/")[:2])
        hour = int(clock.split(":")[0])
        fields = [1999, month, day, hour, 60, "?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9",
                  row.temp_air, row.temp_dew, row.relative_humidity, 99999, 9999, 9999, 9999, row.ghi, row.dni,
                  row.dhi, 999999, 999999, 999999, 9999, 999, 999, 99, 99, 9999, 99999, 9, 999999999, 999,
                  0.999, 999, 99, 999, 999, 99]
        lines.append(",".join(str(f) for f in fields))
    path = folder / "greensboro_tmy3.epw"
    path.write_text(head + "\n".join(lines) + "\n", encoding="utf-8")
    return path


def compare(epw: Path) -> tuple[list[dict], float, float]:
    import skyscatter
    from skyscatter.sky.perez import EPSILON_BIN_EDGES, epsilon_bin

    t0 = time.perf_counter()
    perez = skyscatter.skymatrix(epw, scheme="reinhart2", model="perez")
    t1 = time.perf_counter()
    asrc = skyscatter.skymatrix(epw, scheme="reinhart2", model="asrc-cie")
    t2 = time.perf_counter()
    lit = perez.diffuse_illuminance > 0
    assert np.array_equal(lit, asrc.diffuse_illuminance > 0)
    lp, la = perez.luminance[lit], asrc.luminance[lit]
    bins = epsilon_bin(perez.epsilon[lit])
    g = perez.scheme
    zenith = g.n_patches - 1
    lowest = np.flatnonzero(g.centre_altitude == g.centre_altitude.min())
    rms_rel = np.sqrt(np.mean((la - lp) ** 2, axis=1)) / lp.mean(axis=1)
    brightest = np.argmax(lp, axis=1)
    rows = []
    edges = [*EPSILON_BIN_EDGES, np.inf]
    for b in [*range(8), None]:
        sel = np.ones(bins.size, bool) if b is None else bins == b
        if not sel.any():
            continue
        d = la[sel] - lp[sel]
        rows.append({
            "bin": "all" if b is None else f"{b + 1} ({edges[b]:g}-{edges[b + 1]:g})",
            "hours": int(sel.sum()),
            "median": float(np.median(rms_rel[sel])),
            "p90": float(np.percentile(rms_rel[sel], 90)),
            "pooled": float(np.sqrt(np.sum(d**2) / np.sum(lp[sel] ** 2))),
            "zenith": float(np.median(la[sel, zenith] / lp[sel, zenith])),
            "circumsolar": float(np.median(la[sel, brightest[sel]] / lp[sel, brightest[sel]])),
            "horizon": float(np.median(la[sel][:, lowest].mean(1) / lp[sel][:, lowest].mean(1))),
        })
    return rows, t1 - t0, t2 - t1


CONDITIONS = [(1.0, 0.05), (1.1, 0.3), (1.8, 0.25), (4.0, 0.15), (8.0, 0.1)]


def figure(path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from skyscatter.conventions import direction_from_angles
    from skyscatter.sky.asrc_cie import ASRCCIESky
    from skyscatter.sky.perez import PerezSky

    sun_zenith, sun_azimuth, d_v = np.radians(55.0), np.radians(180.0), 20_000.0
    n = 241
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(1, -1, n))  # north up, east right
    r = np.hypot(x, y)
    inside = r <= 1.0
    theta = 2 * np.arcsin(np.clip(r, 0, 1) / np.sqrt(2))  # equal-area fisheye
    dirs = direction_from_angles(theta, np.arctan2(x, y))
    fig, axes = plt.subplots(3, len(CONDITIONS), figsize=(3.0 * len(CONDITIONS), 8.6), constrained_layout=True)
    norm = matplotlib.colors.LogNorm(vmin=1e3, vmax=1e5)
    alt = np.linspace(0, 180, 361)  # along the solar meridian, from the horizon under the sun to the opposite one
    meridian = direction_from_angles(np.radians(np.abs(90 - alt)), np.where(alt < 90, sun_azimuth, 0.0))
    for j, (eps, delta) in enumerate(CONDITIONS):
        skies = {"Perez 1993": PerezSky(sun_zenith, sun_azimuth, epsilon=eps, delta=delta, diffuse_illuminance=d_v),
                 "ASRC-CIE": ASRCCIESky(sun_zenith, sun_azimuth, epsilon=eps, delta=delta, diffuse_illuminance=d_v)}
        for i, (name, sky) in enumerate(skies.items()):
            img = np.where(inside, sky.luminance(dirs), np.nan)
            ax = axes[i, j]
            im = ax.imshow(img, norm=norm, cmap="magma", extent=(-1, 1, -1, 1))
            ax.set_xticks([])
            ax.set_yticks([])
            title = f"eps {eps:g}, delta {delta:g}\n{name}"
            if name == "ASRC-CIE":
                short = {"clear": "clear", "turbid": "turbid", "intermediate": "interm.", "overcast": "overcast"}
                title += ": " + ", ".join(f"{short[k]} {v:.2f}" for k, v in sky.weights.items() if v > 0)
            ax.set_title(title, fontsize=8)
            axes[2, j].semilogy(alt, sky.luminance(meridian), label=name)
        axes[2, j].set_xlabel("elevation along the solar meridian [deg]\n(sun at 35; 90 = zenith)", fontsize=8)
        axes[2, j].set_ylim(5e2, 2e5)
        axes[2, j].legend(fontsize=7)
    axes[2, 0].set_ylabel("luminance [cd m^-2]")
    fig.colorbar(im, ax=axes[:2, :], shrink=0.6, label="luminance [cd m^-2] (equal-area fisheye, north up)")
    fig.suptitle(f"Perez 1993 and ASRC-CIE for the same sky condition, D_v = {d_v:g} lx", fontsize=10)
    fig.savefig(path, dpi=110)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--synthetic", action="store_true", help="also the synthetic Munich year of bench_skymatrix.py")
    ap.add_argument("--markdown", action="store_true", help="print Markdown tables")
    ap.add_argument("--figure", type=Path, default=None, help="write the comparison figure (PNG) here")
    args = ap.parse_args(argv)
    if args.figure is not None:
        figure(args.figure)
    with tempfile.TemporaryDirectory() as tmp:
        files = {"Greensboro NC (TMY3)": tmy3_as_epw(Path(tmp))}
        if args.synthetic:
            sys.path.insert(0, str(Path(__file__).parent))
            from bench_skymatrix import write_synthetic_epw

            files["synthetic Munich"] = write_synthetic_epw(Path(tmp) / "munich.epw")
        for name, epw in files.items():
            rows, tp, ta = compare(epw)
            print(f"\n{name}: skymatrix perez {tp:.2f} s, asrc-cie {ta:.2f} s (load {os.getloadavg()[0]:.1f})")
            head = ["Perez bin (epsilon)", "hours", "RMS/mean median", "RMS/mean p90", "pooled RMS", "zenith",
                    "circumsolar", "horizon"]
            if args.markdown:
                print("| " + " | ".join(head) + " |\n|" + "---|" * len(head))
            for r in rows:
                vals = [r["bin"], str(r["hours"]), f"{r['median']:.3f}", f"{r['p90']:.3f}", f"{r['pooled']:.3f}",
                        f"{r['zenith']:.3f}", f"{r['circumsolar']:.3f}", f"{r['horizon']:.3f}"]
                print(("| " + " | ".join(vals) + " |") if args.markdown else "  ".join(f"{v:>12}" for v in vals))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
