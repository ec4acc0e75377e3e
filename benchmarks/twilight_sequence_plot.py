"""A twilight sequence read from the tables: the sky's luminance against the sun's elevation, every 0.05 deg from
-12 to +2 deg, in three directions from the ground (the zenith; 5 deg up towards the sun; 15 deg up away from it),
read three ways (docs/accuracy.md, "The refined sun-zenith read"; the figure docs/images/twilight_read.png):

* the default tables (32 sun-zenith texels) read linearly along the sun zenith (the lookups before 2026-12-05: the
  general per-ray kernel on the stored tables with no cell split);
* the same tables with the lookups' refined sun-zenith axis (the library's read);
* tables of 94 sun-zenith texels (three times denser, the same mapping), as the reference of what the
  precomputation resolves.

Printed: per direction, the median and largest ``|x / x_94 - 1|`` [%] of the two reads of the default tables over
the suns from -7 to -0.5 deg. ``python benchmarks/twilight_sequence_plot.py [--out docs/images/twilight_read.png]``
(the 94-texel tables are computed once, about a minute, if not cached).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from skyscatter.precomputed import cached_atmosphere, lookup

DIRECTIONS = {"zenith": (90.0, 0.0), "5 deg up towards the sun": (5.0, 0.0),
              "15 deg up away from the sun": (15.0, 180.0)}


def unit(elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return np.array([math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)])


def luminance(atm, suns_deg: np.ndarray, refined: bool) -> np.ndarray:
    """Luminance [cd m^-2] (n_suns, n_directions) from the ground, per-ray kernel; ``refined`` False reads the
    stored tables with no sun-zenith cell split (the linear read)."""
    p = atm.parameters
    d = np.array([unit(*v) for v in DIRECTIONS.values()])
    pos = np.broadcast_to([0.0, 0.0, p.bottom_radius + 1.0], d.shape)
    out = np.zeros((suns_deg.size, d.shape[0]))
    tab = atm.lookup_tables if refined else atm.tables
    cells = atm._mu_s_cells if refined else 0
    for k, e in enumerate(np.radians(suns_deg)):
        sun = np.ascontiguousarray(np.broadcast_to([0.0, math.cos(e), math.sin(e)], d.shape))
        rad = np.zeros((d.shape[0], atm.wavelengths.size))
        tr = np.ones_like(rad)
        lookup.sky_kernel(np.ascontiguousarray(pos), d, sun, np.zeros(d.shape[0]), tab["transmittance"],
                          tab["single_rayleigh"], tab["single_mie"], tab["multiple"], tab["irradiance"], atm._albedo,
                          atm._solar, p.bottom_radius, p.top_radius, p.mu_s_min, cells, atm._mie_g, atm._mie_kind,
                          atm._lobe, *atm._aerosol_phase[2:], *atm._profiles, p.sun_angular_radius, True, rad, tr, 0,
                          d.shape[0])
        out[k] = atm.luminance(rad)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "docs" / "images" / "twilight_read.png"))
    args = ap.parse_args()
    default = cached_atmosphere(progress=False)
    fine = cached_atmosphere(sizes={"scattering_mu_s": 94}, progress=False)
    suns = np.arange(-12.0, 2.0 + 1e-9, 0.05)
    lin = luminance(default, suns, False)
    ref = luminance(default, suns, True)
    f94 = luminance(fine, suns, True)
    band = (suns >= -7.0) & (suns <= -0.5)
    for j, name in enumerate(DIRECTIONS):
        e_lin = np.abs(lin[band, j] / f94[band, j] - 1)
        e_ref = np.abs(ref[band, j] / f94[band, j] - 1)
        print(f"{name}: linear median {100 * np.median(e_lin):.1f} % largest {100 * e_lin.max():.1f} %; "
              f"refined median {100 * np.median(e_ref):.1f} % largest {100 * e_ref.max():.1f} %")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from skyscatter.precomputed.kernels import mu_s_texels

    p = default.parameters
    texels = np.degrees(np.arcsin(mu_s_texels(p.bottom_radius, p.top_radius, p.mu_s_min, 32)))
    fig, axes = plt.subplots(2, len(DIRECTIONS), figsize=(13, 6.5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    for j, name in enumerate(DIRECTIONS):
        ax, ax2 = axes[0, j], axes[1, j]
        ax.semilogy(suns, f94[:, j], color="k", lw=2.2, label="94 sun-zenith texels")
        ax.semilogy(suns, lin[:, j], color="tab:red", lw=1.0, label="32 texels, linear read (before)")
        ax.semilogy(suns, ref[:, j], color="tab:blue", lw=1.0, ls="--", label="32 texels, refined read")
        ax.set_title(name)
        ax2.plot(suns, 100 * (lin[:, j] / f94[:, j] - 1), color="tab:red", lw=1.0)
        ax2.plot(suns, 100 * (ref[:, j] / f94[:, j] - 1), color="tab:blue", lw=1.0)
        ax2.axhline(0.0, color="k", lw=0.5)
        ax2.set_ylim(-40, 120)
        for t in texels[texels <= 2.0]:
            ax.axvline(t, color="0.85", lw=0.5, zorder=0)
            ax2.axvline(t, color="0.85", lw=0.5, zorder=0)
        ax2.set_xlabel("sun elevation [deg]")
    axes[0, 0].set_ylabel("luminance [cd m$^{-2}$]")
    axes[1, 0].set_ylabel("against 94 texels [%]")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("Earth defaults, observer on the ground; grey lines: the 32 stored sun-zenith texels")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
