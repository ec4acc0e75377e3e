"""Colour and luminance error of the Bruneton tables' default wavelengths and of the 3-wavelength mode (issue 11).

The reference is the CIE 1931 observer integral (``skyscatter.spectral.spectrum_to_xyz``, trapezoid on the
samples) of the same atmosphere computed at 41 wavelengths, 380-780 nm every 10 nm, default table sizes and
orders. The default wavelengths (``DEFAULT_TABLE_WAVELENGTHS``, 400-700 nm every 20 nm) and the 3-wavelength
mode (``RGB_TABLE_WAVELENGTHS``, 440/550/680 nm) are subsets of that grid. Each wavelength's tables are computed
independently of the others (chunks share only geometry; ``tests/test_bruneton_colour_default.py`` checks that a
subset of a computation equals a separate computation), so by default the two are sliced out of the 41-wavelength
tables; ``--separate`` computes them on their own instead. Their XYZ comes from ``BrunetonSky.xyz`` (the
library's conversion, :mod:`skyscatter.precomputed.conversion`).

Directions seen from the ground: azimuth every 10 deg, elevation -89..-11 every 8 deg, -10..+9.5 every 0.5 deg,
10..85 every 5 deg and 89.9 deg; sky (elevation > 0) and ground (< 0) apart; directions darker than 1e-6 of the
brightest of their sky are left out (none above -6 deg). Reported per sun elevation: the largest chromaticity
difference ``|xy - xy_ref|`` and the largest relative luminance difference, and the zenith's chromaticity.

Usage: ``python benchmarks/bruneton_colour_error.py [--tables FILE.npz] [--save FILE.npz] [--separate]``
(about 2.5 min for the 41-wavelength tables on the 2-core machine, seconds with ``--tables``).
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

ELEVATIONS = (90.0, 30.0, 10.0, 2.0, 0.0, -2.0, -4.0, -6.0)
REFERENCE_WAVELENGTHS = np.arange(380.0, 781.0, 10.0)


def directions() -> np.ndarray:
    az = np.radians(np.arange(0.0, 360.0, 10.0))
    el = np.radians(np.concatenate([np.arange(-89.0, -10.0, 8.0), np.arange(-10.0, 10.0, 0.5),
                                    np.arange(10.0, 90.0, 5.0), [89.9]]))
    a, e = np.meshgrid(az, el)
    return np.stack([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)], axis=-1).reshape(-1, 3)


def subset(atm, wavelengths):
    from skyscatter.precomputed import PrecomputedAtmosphere

    idx = [int(np.argmin(np.abs(atm.wavelengths - w))) for w in wavelengths]
    if not np.allclose(atm.wavelengths[idx], wavelengths):
        raise SystemExit(f"{wavelengths} is not a subset of the reference wavelengths")
    return PrecomputedAtmosphere(atm.parameters, atm.wavelengths[idx], atm.sizes, atm.orders,
                                 {k: v[..., idx] for k, v in atm.tables.items()}, computed=True)


def chromaticity(xyz: np.ndarray) -> np.ndarray:
    return xyz[..., :2] / np.sum(xyz, axis=-1, keepdims=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tables", help="41-wavelength tables saved by an earlier run (--save)")
    ap.add_argument("--save", help="save the 41-wavelength tables here")
    ap.add_argument("--separate", action="store_true", help="compute the default and 3-wavelength tables apart")
    args = ap.parse_args()

    from skyscatter.precomputed import PrecomputedAtmosphere
    from skyscatter.precomputed.tables import DEFAULT_TABLE_WAVELENGTHS, RGB_TABLE_WAVELENGTHS
    from skyscatter.sky.bruneton import BrunetonSky
    from skyscatter.spectral import spectrum_to_xyz

    if args.tables:
        ref = PrecomputedAtmosphere.load(args.tables)
        if not np.array_equal(ref.wavelengths, REFERENCE_WAVELENGTHS):
            raise SystemExit(f"{args.tables} does not hold 380-780 nm every 10 nm")
    else:
        t0 = time.perf_counter()
        ref = PrecomputedAtmosphere.compute(wavelengths=REFERENCE_WAVELENGTHS, progress=False)
        print(f"41-wavelength tables: {time.perf_counter() - t0:.1f} s")
        if args.save:
            ref.save(args.save)
    modes = {}
    for name, wl in (("default", DEFAULT_TABLE_WAVELENGTHS), ("3-wavelength", RGB_TABLE_WAVELENGTHS)):
        if args.separate:
            modes[name] = PrecomputedAtmosphere.compute(ref.parameters, orders=ref.orders, wavelengths=wl,
                                                        sizes=ref.sizes, progress=False)
        else:
            modes[name] = subset(ref, np.asarray(wl))
    d = directions()
    ground = d[:, 2] < 0.0
    print(f"reference: 41 wavelengths 380-780 nm, sizes {ref.sizes.scattering_shape}, {ref.orders} orders; "
          f"{d.shape[0]} directions ({int(ground.sum())} ground)")
    print("| sun elevation | default: max delta-xy sky / ground | default: max luminance error sky / ground "
          "| 3-wavelength: max delta-xy sky / ground | 3-wavelength: max luminance error sky / ground "
          "| zenith xy: 41 wl / default / 3 wl |")
    print("|---|---|---|---|---|---|")
    worst = {name: [0.0, 0.0] for name in modes}
    for el in ELEVATIONS:
        zen, azi = math.radians(90.0 - el), 0.0
        xyz_ref = spectrum_to_xyz(BrunetonSky(zen, azi, precomputed=ref).table_radiance(d), ref.wavelengths)
        y_ref = xyz_ref[:, 1]
        lit = y_ref > 1e-6 * y_ref.max()
        cells, zenith = [], [chromaticity(xyz_ref[-1])]
        for name, atm in modes.items():
            xyz = BrunetonSky(zen, azi, precomputed=atm).xyz(d)
            dxy = np.hypot(*(chromaticity(xyz) - chromaticity(xyz_ref)).T)
            dlum = np.abs(xyz[:, 1] / y_ref - 1.0)
            parts = [(dxy[lit & ~ground].max(), dxy[lit & ground].max()),
                     (dlum[lit & ~ground].max(), dlum[lit & ground].max())]
            worst[name][0] = max(worst[name][0], *parts[0])
            worst[name][1] = max(worst[name][1], *parts[1])
            cells += [f"{parts[0][0]:.4f} / {parts[0][1]:.4f}",
                      f"{100 * parts[1][0]:.2f} % / {100 * parts[1][1]:.2f} %"]
            zenith.append(chromaticity(xyz[-1]))
        zcell = " / ".join(f"({z[0]:.3f}, {z[1]:.3f})" for z in zenith)
        print(f"| {el:+.0f} deg | " + " | ".join(cells) + f" | {zcell} |")
    for name, (dxy, dlum) in worst.items():
        print(f"{name}: worst delta-xy {dxy:.4f} (bound 0.005), worst luminance error {100 * dlum:.2f} % (bound 2 %)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
