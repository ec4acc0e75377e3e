"""Fit the Hosek-Wilkie form to the precomputed (Bruneton) atmosphere; compare with the published model.

Run: python benchmarks/fit_hosek_wilkie_bruneton.py [OUT_DIR]   (default docs/images; prints the tables of
docs/hosek_wilkie.md and writes its plots). The default tables take ~30 s to build the first time (cached).

* fit: :func:`skyscatter.fit.fit_hosek_wilkie` on ``BrunetonSky`` (Earth defaults: Rayleigh, ozone, aerosol
  optical depth 0.0053 with Angstrom alpha 0, ground albedo 0.1) at 440, 550 and 680 nm, 10 sun elevations even
  in t; timed.
* test: RMS relative error over the sky >= 5 deg above the horizon and >= 5 deg from the sun, at sun elevations
  halfway (in t) between the fitted ones, and over the band 0-5 deg above the horizon.
* published: the Hosek-Wilkie model with matched aerosol. The default atmosphere's turbidity is
  (tau_R + tau_A) / tau_R = 1.05 at 550 nm, so T = 1 (the smallest the data allow), albedo 0.1.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from skyscatter import BrunetonSky, HosekWilkieSky
from skyscatter.conventions import direction_from_angles
from skyscatter.fit import fit_hosek_wilkie, fit_sun_elevations, sky_fit_error

WL = np.array([440.0, 550.0, 680.0])


def horizon_band_error(fitted, source, wl, n=2000) -> np.ndarray:
    rng = np.random.default_rng(1)
    d = direction_from_angles(np.arccos(rng.uniform(0.0, np.sin(np.radians(5)), n)), rng.uniform(0, 2 * np.pi, n))
    d = d[d @ source.sun_direction < np.cos(np.radians(5))]
    return np.sqrt(np.mean((fitted.spectral_radiance(d, wl) / source.spectral_radiance(d, wl) - 1) ** 2, axis=0))


def main(out_dir: Path) -> None:
    make = lambda z, a: BrunetonSky(z, a)  # noqa: E731
    make(0.5, 0.0).spectral_radiance(np.array([0, 0, 1.0]), WL)  # build or load the tables
    t0 = time.perf_counter()
    ds = fit_hosek_wilkie(make, WL, provenance={"atmosphere": "skyscatter AtmosphereParameters() Earth defaults"})
    fit_seconds = time.perf_counter() - t0
    print(f"fit: {WL.size} wavelengths, {fit_seconds:.1f} s (sampling {ds.provenance['fit']['sampling_seconds']} s)")
    t_fit = np.power(fit_sun_elevations() / (np.pi / 2), 1 / 3)
    t_test = 0.5 * (t_fit[:-1] + t_fit[1:])
    test_elev = t_test**3 * 90.0
    rows = []
    print("sun elev [deg] | fit RMS >=5 deg (440/550/680) | fit RMS 0-5 deg band | published T=1 RMS >=5 deg")
    for e in test_elev:
        z = np.radians(90 - e)
        src = make(z, 0.3)
        fitted = HosekWilkieSky(z, 0.3, dataset=ds)
        published = HosekWilkieSky(z, 0.3, turbidity=1.0, ground_albedo=0.1)
        a = sky_fit_error(fitted, src, WL)
        b = horizon_band_error(fitted, src, WL)
        c = sky_fit_error(published, src, WL)
        rows.append((e, a, b, c))
        print(f"{e:8.3f} | {' '.join(f'{v * 100:5.2f}%' for v in a)} | {' '.join(f'{v * 100:5.2f}%' for v in b)} | "
              f"{' '.join(f'{v * 100:6.1f}%' for v in c)}")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    colours = ("tab:blue", "tab:green", "tab:red")
    for k, w in enumerate(WL):
        c = colours[k]
        ax[0].semilogy([r[0] for r in rows], [r[1][k] * 100 for r in rows], "o-", color=c,
                       label=f"{w:g} nm, sky >= 5 deg")
        ax[0].semilogy([r[0] for r in rows], [r[2][k] * 100 for r in rows], "s--", color=c,
                       label=f"{w:g} nm, 0-5 deg above horizon")
        ax[1].plot([r[0] for r in rows], [r[3][k] * 100 for r in rows], "o-", color=c, label=f"{w:g} nm")
    ax[0].axhline(5, color="k", lw=0.8, label="5 % target")
    ax[0].set(xscale="log", xlabel="sun elevation [deg] (between fitted elevations)", ylabel="RMS relative error [%]",
              title="Hosek-Wilkie form fitted to the precomputed atmosphere")
    ax[1].set(xscale="log", xlabel="sun elevation [deg]", ylabel="RMS relative error [%]",
              title="published Hosek-Wilkie (T=1, albedo 0.1) vs precomputed")
    ax[0].legend(fontsize=7)
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out_dir / "hosek_wilkie_fit_errors.png", dpi=110)
    # radiance along the solar vertical (through the zenith) at 550 nm for two sun elevations
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    vza = np.radians(np.linspace(-89.5, 89.5, 721))
    for axx, e in zip(axes, (5.0, 35.0), strict=True):
        z = np.radians(90 - e)
        d = direction_from_angles(np.abs(vza), np.where(vza < 0, np.pi, 0.0))
        for sky, label in ((make(z, 0.0), "precomputed (Bruneton)"),
                           (HosekWilkieSky(z, 0.0, dataset=ds), "fitted form"),
                           (HosekWilkieSky(z, 0.0, turbidity=1.0, ground_albedo=0.1), "published HW T=1")):
            axx.semilogy(np.degrees(vza), sky.spectral_radiance(d, [550.0])[:, 0], label=label)
        axx.set(xlabel="view zenith angle in the solar vertical [deg] (sun side > 0)",
                ylabel="radiance at 550 nm [W m-2 sr-1 nm-1]", title=f"sun elevation {e:g} deg")
        axx.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_dir / "hosek_wilkie_solar_vertical.png", dpi=110)


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "images"
    out.mkdir(parents=True, exist_ok=True)
    main(out)
