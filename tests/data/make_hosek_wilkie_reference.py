"""Generate ``hosek_wilkie_reference.csv``: values printed by the authors' Hosek-Wilkie C reference code.

A one-off, independent check (not run by the tests). Provenance of the stored file:

* C sources: ``src/ext/skymodel/ArHosekSkyModel.{c,h}`` and ``ArHosekSkyModelData_{Spectral,CIEXYZ,RGB}.h`` of
  https://github.com/mmp/pbrt-v4 at commit 5f7a606806a4ac7b939131ded9d7a30ebd02416e (the authors' release 1.4a,
  BSD-3-Clause, Copyright (c) 2012-2013 Lukas Hosek and Alexander Wilkie), unmodified;
* compiled with gcc 12.2.0 (``gcc -O0 -std=c99 -D_GNU_SOURCE ref.c ArHosekSkyModel.c -lm``) together with the
  ~30-line driver ``hosek_wilkie_reference_driver.c`` next to this file, which reads one case per line and prints
  the result of one reference entry point with ``%.17g``;
* kinds: 0 ``arhosekskymodel_radiance`` (spectral sky), 1/2 ``arhosek_tristim_skymodel_radiance`` on the XYZ/RGB
  states (``channel`` in the wavelength column), 3 ``arhosekskymodel_solar_radiance`` (sky + sun),
  4 ``arhosekskymodel_solar_radiance_internal2`` (sun alone, view elevation = pi/2 - theta).

The cases are random (seed 2012) plus edge values: sun on the horizon and in the zenith, turbidity 1 and
exactly 10, albedo 0 and 1, view on the horizon and at the zenith. The view direction is stored as a unit ENU
vector; the C code got theta = acos(z) and gamma = atan2(|d x s|, d . s).

Usage: ``python tests/data/make_hosek_wilkie_reference.py PATH_TO_COMPILED_DRIVER``
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np


def direction(zenith: float, azimuth: float) -> np.ndarray:
    return np.array([np.sin(zenith) * np.sin(azimuth), np.sin(zenith) * np.cos(azimuth), np.cos(zenith)])


def cases(rng: np.random.Generator) -> list[tuple]:
    rows = []
    configs = [(1.0, 0.0, 0.0), (10.0, 1.0, np.pi / 2), (10.0, 0.0, 0.3), (1.0, 1.0, 1e-3), (9.999, 0.5, 0.05)]
    configs += [(rng.uniform(1, 10), rng.uniform(0, 1), rng.uniform(0, np.pi / 2) * rng.uniform() ** 1.5)
                for _ in range(10)]
    for t, a, sun_zen_elev in configs:
        sun_zen = np.pi / 2 - sun_zen_elev
        sun_azi = rng.uniform(0, 2 * np.pi)
        dirs = [direction(np.pi / 2, rng.uniform(0, 2 * np.pi)), direction(0.0, 0.0)]
        dirs += [direction(np.arccos(rng.uniform(0, 1)), rng.uniform(0, 2 * np.pi)) for _ in range(4)]
        dirs.append(direction(sun_zen, sun_azi + 0.02))  # near the sun
        for d in dirs:
            for wl in (320.0, 360.0, 555.0, 560.0, 600.5, rng.uniform(320, 720), 720.0):
                rows.append((0, t, a, sun_zen, sun_azi, *d, wl))
            for ch in (0, 1, 2):
                rows.append((1, t, a, sun_zen, sun_azi, *d, ch))
                rows.append((2, t, a, sun_zen, sun_azi, *d, ch))
        # the solar disc: centre and points at several fractions of the radius
        r = np.radians(0.51) / 2
        for frac in (0.0, 0.3, 0.7, 0.95):
            off = frac * r
            d = direction(sun_zen - off, sun_azi) if sun_zen - off >= 0 else direction(off - sun_zen, sun_azi + np.pi)
            if d[2] < 0:
                continue
            for wl in (320.0, 440.0, 555.0, 701.0, 720.0):
                rows.append((4, t, a, sun_zen, sun_azi, *d, wl))
                rows.append((3, t, a, sun_zen, sun_azi, *d, wl))
    return rows


def main(driver: str) -> None:
    rows = cases(np.random.default_rng(2012))
    lines = []
    for kind, t, a, zen, azi, dx, dy, dz, w in rows:
        s = direction(zen, azi)
        d = np.array([dx, dy, dz])
        gamma = float(np.arctan2(np.linalg.norm(np.cross(d, s)), d @ s))
        theta = float(np.arccos(np.clip(dz, -1, 1)))
        lines.append(f"{kind} {t!r} {a!r} {np.pi / 2 - zen!r} {theta!r} {gamma!r} {w!r}")
    out = subprocess.run([driver], input="\n".join(lines) + "\n", capture_output=True, text=True, check=True)
    values = out.stdout.split()
    assert len(values) == len(rows)
    path = Path(__file__).with_name("hosek_wilkie_reference.csv")
    with open(path, "w") as fh:
        fh.write("# Hosek-Wilkie 1.4a reference C code output; see make_hosek_wilkie_reference.py for provenance\n")
        fh.write("kind,turbidity,albedo,sun_zenith,sun_azimuth,dx,dy,dz,wavelength_or_channel,value\n")
        for row, v in zip(rows, values, strict=True):
            fh.write(",".join(repr(float(x)) for x in row[1:]).join([f"{row[0]},", f",{v}\n"]))
    print(f"wrote {len(rows)} rows to {path}")


if __name__ == "__main__":
    main(sys.argv[1])
