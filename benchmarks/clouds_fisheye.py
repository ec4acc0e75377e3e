"""Fisheye pictures of two Monte Carlo skies with clouds (docs/images/clouds_fisheye_*.png, docs/clouds.md).

* broken clouds: a procedural field (cover 0.4, base 1000 m, highest tops 2500 m, mean optical depth 10 of the
  cloudy columns, 16 km periodic domain at 96 x 96 x 24 voxels, seed 3) of Mie droplets (r_e 10 um);
* overcast: a uniform layer of optical depth 15 from 1000 to 1500 m (the same droplets).

Earth air (Rayleigh, the default aerosol, ozone), ground albedo 0.2, sun 35 deg above the horizon in the
south-east (azimuth 135 deg). Equidistant fisheye looking up, north at the top and east on the right (as seen
on a map), 64 x 64 pixels, 8 wavelengths 420-700 nm sharing each path (``--samples`` paths per pixel, default
256), converted to CIE XYZ and linear sRGB, tone mapped with the automatic exposure. The solar disc is not drawn
(the Monte Carlo reports it separately). Usage: ``python benchmarks/clouds_fisheye.py [--samples N] [--size N]``.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.atmosphere.clouds import CloudField, CloudLayer
from skyscatter.montecarlo import sky_radiance
from skyscatter.render.image_io import write_png
from skyscatter.spectral import spectrum_to_xyz, xyz_to_linear_srgb

OUT = Path(__file__).parents[1] / "docs" / "images"
WL = np.linspace(420.0, 700.0, 8)


def fisheye_directions(size: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit directions (ENU) of the pixels inside the circle of an equidistant fisheye looking up (north up, east
    right) and the mask of those pixels."""
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    x, y = np.meshgrid(c, -c)  # x: east, y: north (image rows go south)
    r = np.hypot(x, y)
    inside = r < 1.0
    zen = r * math.pi / 2
    az = np.arctan2(x, y)
    d = np.stack([np.sin(zen) * np.sin(az), np.sin(zen) * np.cos(az), np.cos(zen)], axis=-1)
    return d[inside], inside


def render(atm, clouds, sun_zenith, sun_azimuth, size, samples, seed):
    dirs, inside = fisheye_directions(size)
    t0 = time.perf_counter()
    res = sky_radiance(atm, dirs, WL, sun_zenith=sun_zenith, sun_azimuth=sun_azimuth, samples=samples, seed=seed,
                       clouds=clouds)
    rgb = np.zeros((size, size, 3))
    rgb[inside] = xyz_to_linear_srgb(spectrum_to_xyz(res.radiance, WL) / 683.0)
    return rgb, res, time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=256)
    ap.add_argument("--size", type=int, default=64)
    args = ap.parse_args()
    print(f"machine: {len(os.sched_getaffinity(0))} cores, load average {os.getloadavg()[0]:.1f}")
    air = AtmosphereParameters(ground_albedo=0.2)
    drops = CloudLayer(0.0, 1.0, 1.0, effective_radius=10e-6)  # its optics only (the field's particles)
    broken = CloudField.procedural(cover=0.4, base=1000.0, top=2500.0, particles=drops, optical_depth=10.0,
                                   size=16_000.0, resolution=(96, 96, 24), feature_size=4000.0, seed=3)
    overcast = air.replace(particles=(CloudLayer(1000.0, 1500.0, 15.0, effective_radius=10e-6),))
    sz, sa = math.radians(55.0), math.radians(135.0)
    for name, atm, field in (("broken", air, broken), ("overcast", overcast, None)):
        rgb, res, secs = render(atm, field, sz, sa, args.size, args.samples, seed=5)
        path = write_png(OUT / f"clouds_fisheye_{name}.png", rgb, key=0.4)
        print(f"{name}: {path} ({res.samples} paths per pixel, {res.mean_vertices:.1f} events per path, median "
              f"relative stderr {np.median(res.relative_stderr):.2f}, {secs:.0f} s)")
        if field is not None:
            print(f"   field: cloud fraction {field.cloud_fraction():.2f}, mean optical depth of cloudy columns "
                  f"{field.optical_depth()[field.optical_depth() > 0].mean():.1f}")


if __name__ == "__main__":
    main()
