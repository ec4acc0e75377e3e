"""An overcast sky from the fast model (``CloudySky``) beside the Monte Carlo's, the same fisheye and exposure
(docs/images/cloudy_fisheye_fast_vs_mc.png, docs/clouds.md "Fast cloud layers").

A uniform water cloud of optical depth 15 from 1000 to 1500 m (Mie droplets r_e 10 um), Earth air, ground albedo
0.2, sun 35 deg above the horizon in the south-east (azimuth 135 deg), as ``benchmarks/clouds_fisheye.py``:
equidistant fisheye looking up, north at the top and east on the right (as seen on a map), ``--size`` pixels
square, 8 wavelengths 420-700 nm, ``--samples`` Monte Carlo paths per pixel; the two images side by side in one
PNG (one automatic exposure for both), the solar disc not drawn. Prints the ratio of the images' mean
luminances and the median per-pixel ratio.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path

import numpy as np

from clouds_fisheye import WL, fisheye_directions
from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.atmosphere.clouds import CloudLayer
from skyscatter.montecarlo import sky_radiance
from skyscatter.render.image_io import write_png
from skyscatter.sky.cloudy import CloudySky
from skyscatter.spectral import spectrum_to_xyz, xyz_to_linear_srgb

OUT = Path(__file__).parents[1] / "docs" / "images"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=128)
    ap.add_argument("--size", type=int, default=64)
    a = ap.parse_args()
    print(f"load average {os.getloadavg()}")
    dirs, inside = fisheye_directions(a.size)
    sz, sa = math.radians(55.0), math.radians(135.0)
    t0 = time.perf_counter()
    fast = CloudySky(sz, sa, cloud_optical_depth=15.0, cloud_base=1000.0, cloud_top=1500.0, ground_albedo=0.2)
    l_fast = fast.spectral_radiance(dirs, WL)
    t_fast = time.perf_counter() - t0
    atm = AtmosphereParameters(ground_albedo=0.2, particles=(CloudLayer(1000.0, 1500.0, 15.0),))
    t0 = time.perf_counter()
    res = sky_radiance(atm, dirs, WL, sun_zenith=sz, sun_azimuth=sa, samples=a.samples, seed=5)
    t_mc = time.perf_counter() - t0
    img = np.zeros((a.size, 2 * a.size + 4, 3))
    for k, rad in enumerate((l_fast, res.radiance)):
        rgb = np.zeros((a.size, a.size, 3))
        rgb[inside] = xyz_to_linear_srgb(spectrum_to_xyz(rad, WL) / 683.0)
        img[:, k * (a.size + 4): k * (a.size + 4) + a.size] = rgb
    path = write_png(OUT / "cloudy_fisheye_fast_vs_mc.png", np.repeat(np.repeat(img, 4, axis=0), 4, axis=1), key=0.4)
    y_fast = spectrum_to_xyz(l_fast, WL)[:, 1]
    y_mc = spectrum_to_xyz(res.radiance, WL)[:, 1]
    # the Monte Carlo's per-pixel values are heavy-tailed (most pixels low, a few hot); their means over bands of
    # elevation, hundreds of pixels each, are the radiance check
    elev = np.degrees(np.arcsin(np.clip(dirs[:, 2], -1.0, 1.0)))
    for lo, hi in ((10.0, 30.0), (30.0, 60.0), (60.0, 90.0)):
        band = (elev >= lo) & (elev < hi)
        m = res.radiance[band].mean(axis=0)
        e = np.sqrt((res.stderr[band] ** 2).sum(axis=0)) / band.sum()
        f = l_fast[band].mean(axis=0)
        print(f"elevation {lo:g}-{hi:g} deg ({band.sum()} pixels): fast / MC "
              f"{' '.join(f'{v:.3f}' for v in f / m)} at {' '.join(f'{w:g}' for w in WL)} nm (MC +- "
              f"{' '.join(f'{v:.3f}' for v in e / m)})")
    print(f"{path}: fast {t_fast:.2f} s, Monte Carlo {t_mc:.0f} s ({res.samples} paths per pixel, median relative "
          f"stderr {np.median(res.relative_stderr):.2f}); mean luminance fast / MC {y_fast.mean() / y_mc.mean():.3f}, "
          f"median per-pixel ratio {np.median(y_fast / y_mc):.3f}")


if __name__ == "__main__":
    main()
