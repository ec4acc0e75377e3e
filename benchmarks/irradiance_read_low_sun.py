"""The irradiance table's read along the sun zenith below the horizon against a table 8x finer (docs/accuracy.md,
"Low sun").

One precomputation with ``irradiance_mu_s = 8 x 63 + 1`` (505) sun-zenith texels (``orders=2``: the irradiance
table is the first order's sky light, whose texels below the horizon come from the scattering tables alone, so the
coarse table is every 8th texel of the fine one exactly); the default 64-texel table is that subsample. The read
of the coarse table (``sampling.irradiance_read``: each wavelength its own weight; and, for comparison, one weight
for all wavelengths from the columns' illuminance, the lookups' read in table formats 15-18, here as
``one_weight_read``) at every fine texel between ``--lo`` and ``--hi`` deg of sun elevation is compared with the
fine texel there, per wavelength, on the ground row (read at its texel, so only the mu_s interpolation is measured);
and in linear sRGB (``realtime.export.fold_matrix``): the three reads folded into colour, and the read of the colour
table itself with a weight per channel (the GLSL library's ``IrradianceLerp``), against the folded fine texel.
The fine texels are not a perfect reference: each is log-quadratic between the scattering tables' three nearest
sun-zenith texels, and where that node set changes (about -5.2, -3.6, -1.8 deg) ``ln E`` steps by up to 0.1 at
400 nm; the hemisphere integral of ``benchmarks/second_order_low_sun.py --irradiance`` is the independent one.

``python benchmarks/irradiance_read_low_sun.py [--atm turbidity3] [--lo -7 --hi 2] [--save fine.npz]``
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from skyscatter.precomputed import AtmosphereParameters, PrecomputedAtmosphere
from skyscatter.precomputed.geometry import irradiance_log_cell, irradiance_log_nodes, log_quadratic_weight
from skyscatter.precomputed.sampling import irradiance_read
from skyscatter.realtime.export import fold_matrix
from skyscatter.spectral import spectrum_to_xyz

ATMOSPHERES = {
    "earth": lambda **k: AtmosphereParameters(**k),
    "turbidity3": lambda **k: AtmosphereParameters.from_turbidity(3.0, **k),
    "aod05": lambda **k: AtmosphereParameters.from_aerosol_optical_depth(0.5, **k),
}
FINE = 8


def one_weight_read(table: np.ndarray, p_r: float, p_m: float, weights: np.ndarray, out: np.ndarray) -> None:
    """The read of ``sampling.irradiance_read`` with one weight along mu_s for every wavelength, that of the three
    columns' weighted sums ``sum_k weights[k] E_k`` (the rendering lookups' read in table formats 15-18, with the
    luminance weights), at index positions (p_r, p_m) of a table (n_r, n_mu_s, n_wavelengths)."""
    n0, n1, _ = table.shape
    i = min(int(p_r), n0 - 2)
    w0 = p_r - i
    j = min(int(p_m), n1 - 2)
    if not irradiance_log_cell(j, n1):
        w1 = p_m - j
        row = (1.0 - w0) * table[i] + w0 * table[i + 1]
        out[:] = (1.0 - w1) * row[j] + w1 * row[j + 1]
        return
    j0, t = irradiance_log_nodes(p_m, n1)
    c = j0 if t < 0.0 else j0 + 1
    row = (1.0 - w0) * table[i] + w0 * table[i + 1]
    y = row[j0:j0 + 3] @ weights
    g = log_quadratic_weight(y[0], y[1], y[2], t)
    out[:] = row[c] + g * (row[c + 1] - row[c])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--atm", default="turbidity3", choices=sorted(ATMOSPHERES))
    ap.add_argument("--lo", type=float, default=-7.0)
    ap.add_argument("--hi", type=float, default=2.0)
    ap.add_argument("--load", default="", help="npz of a previous --save (skips the precomputation)")
    ap.add_argument("--save", default="")
    args = ap.parse_args()
    if args.load:
        z = np.load(args.load)
        fine, lum, wl, fold = z["fine"], z["lum"], z["wl"], z["fold"]
    else:
        params = ATMOSPHERES[args.atm]()
        t0 = time.process_time()
        atm = PrecomputedAtmosphere.compute(params, orders=2, sizes={"irradiance_mu_s": FINE * 63 + 1},
                                            progress=False)
        print(f"# {args.atm}: tables {time.process_time() - t0:.0f} CPU-s")
        fine = np.asarray(atm.tables["irradiance"], dtype=np.float64)
        # the luminance weights of the wavelengths (ybar times the trapezoid step: the illuminance of a spectrum)
        lum = np.maximum(spectrum_to_xyz(np.eye(atm.wavelengths.size), atm.wavelengths)[:, 1], 0.0)
        wl = np.asarray(atm.wavelengths)
        fold = fold_matrix(atm)
        if args.save:
            np.savez(args.save, fine=fine, lum=lum, wl=wl, fold=fold)
    coarse = np.ascontiguousarray(fine[:, ::FINE])
    coarse_rgb = np.ascontiguousarray(coarse @ fold.T)
    rgb = np.empty(3)
    out = np.empty(fine.shape[2])
    print(f"# {fine.shape[2]} wavelengths {wl[0]:g}-{wl[-1]:g} nm; read / fine texel - 1 [%]: worst wavelength "
          "(illuminance weight | own weights), and the illuminance")
    print("| sun [deg] | frac | row | illum. weight: min / max over wl | own: min / max | illuminance | "
          "RGB min / max: illum. weight | own | per channel |")
    print("|---|---|---|---|---|---|---|---|---|")
    worst = {"lum": 0.0, "own": 0.0, "rgb_lum": 0.0, "rgb_own": 0.0, "rgb_channel": 0.0}
    for jf in range(fine.shape[1]):
        mu_s = 2.0 * jf / (fine.shape[1] - 1) - 1.0
        el = math.degrees(math.asin(mu_s))
        if not args.lo <= el <= args.hi:
            continue
        p = jf / FINE
        for row in (0,):
            truth = fine[row, jf]
            t_rgb = fold @ truth
            one_weight_read(coarse, float(row), p, lum, out)
            e_l = out / truth - 1.0
            y = (lum @ out) / (lum @ truth) - 1.0
            c_l = fold @ out / t_rgb - 1.0
            irradiance_read(coarse, float(row), p, out)
            e_o = out / truth - 1.0
            c_o = fold @ out / t_rgb - 1.0
            irradiance_read(coarse_rgb, float(row), p, rgb)
            c_c = rgb / t_rgb - 1.0
            for key, e in (("lum", e_l), ("own", e_o), ("rgb_lum", c_l), ("rgb_own", c_o), ("rgb_channel", c_c)):
                worst[key] = max(worst[key], np.abs(e).max())
            cols = " | ".join(f"{100 * e.min():+.2f} / {100 * e.max():+.2f}" for e in (e_l, e_o))
            rgbs = " | ".join(f"{100 * e.min():+.2f} / {100 * e.max():+.2f}" for e in (c_l, c_o, c_c))
            print(f"| {el:+.2f} | {p - math.floor(p):.3f} | {row} | {cols} | {100 * y:+.2f} | {rgbs} |")
    print(f"# worst |error| {args.lo:g}..{args.hi:g} deg: illuminance weight {100 * worst['lum']:.2f} %, "
          f"own weights {100 * worst['own']:.2f} %; RGB: illuminance weight {100 * worst['rgb_lum']:.2f} %, "
          f"own weights {100 * worst['rgb_own']:.2f} %, weight per channel {100 * worst['rgb_channel']:.2f} %")


if __name__ == "__main__":
    main()
