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


def cct(spectrum, wl):
    import colour

    from skyscatter.spectral import spectrum_to_xyz, xyz_to_chromaticity

    xy = np.asarray(xyz_to_chromaticity(spectrum_to_xyz(spectrum, wl)))[:2]
    return float(np.squeeze(colour.temperature.xy_to_CCT(xy, method="Hernandez 1999")))


def reference_diffuse(case):
    """(values, stderr, kind): the reference diffuse irradiance of a stored case (docs/clouds.md).

    Sun 2 deg: the backward paths (forward photons' periodic domain in a sphere is off there, -7..-34 % under
    the layers); they are heavy-tailed where the direct sun lights the cloud top (650 nm): 20000 paths were
    8-37 % low with standard errors of 2-4 %, so only cases with >= 400000 paths are a reference ("backward"),
    the others are marked "backward (20000, low in the red)". Sun 10 deg: forward photons under a cloud (their
    domain term is at most 1.6 % there: the same photons on planets of 1, 4 and 1000 Earth radii), the backward
    paths in clear air (forward -2.4..-3.2 % there). Higher suns: forward photons."""
    sun, tau = case["sun_elevation_deg"], case["tau"]
    if sun < 5.0 or (sun <= 10.0 and tau == 0.0):
        if "diffuse_irradiance_backward" not in case:
            return None, None, ""
        kind = "backward" if case.get("backward_paths", 0) >= 400000 or tau == 0.0 else \
            f"backward ({case.get('backward_paths')}, low in the red)"
        return (np.array(case["diffuse_irradiance_backward"]), np.array(case["diffuse_irradiance_backward_stderr"]),
                kind)
    if "diffuse_irradiance" not in case:
        return None, None, ""
    return np.array(case["diffuse_irradiance"]), np.array(case["diffuse_irradiance_stderr"]), "forward"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=str(HERE / "tests" / "data" / "cloudy_montecarlo.json"))
    ap.add_argument("--streams", type=int, default=16)
    ap.add_argument("--illumination", default="tables")
    a = ap.parse_args()
    data = json.loads(Path(a.data).read_text())
    wl = data["wavelengths_nm"]
    fine = np.arange(380.0, 781.0, 5.0)
    print("| tau | sun | diffuse E vs MC (450 / 550 / 650 nm) | MC stderr | MC method | radiance >= 10 deg: median, "
          "max "
          "abs (MC median stderr) | CCT model / MC estimate | solve s |")
    print("|---|---|---|---|---|---|---|---|")
    for case in sorted(data["cases"], key=lambda c: (-c["sun_elevation_deg"], c["tau"])):
        tau, sun = case["tau"], case["sun_elevation_deg"]
        t0 = time.perf_counter()
        sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=data["cloud_base_m"],
                        cloud_top=data["cloud_top_m"], ground_albedo=data["ground_albedo"], streams=a.streams,
                        illumination=a.illumination)
        diffuse = sky.diffuse_fluxes(wl)[0]
        dt = time.perf_counter() - t0
        mc_e, mc_ee, kind = reference_diffuse(case)
        if mc_e is None:
            print(f"| {tau:g} | {sun:g} | (no valid Monte Carlo irradiance) | | | | | {dt:.2f} |")
            continue
        d_e = diffuse / mc_e - 1.0
        views = case.get("views_deg", [])
        keep = [i for i, (h, _) in enumerate(views) if h >= 10.0]
        rad_text = "-"
        if keep:
            L = sky.spectral_radiance(directions([views[i] for i in keep]), wl)
            mc_l = np.array(case["radiance"])[keep]
            mc_le = np.array(case["radiance_stderr"])[keep]
            d_l = L / mc_l - 1.0
            rad_text = (f"{np.median(np.abs(d_l)) * 100:.1f} %, {np.max(np.abs(d_l)) * 100:.1f} % "
                        f"({np.median(mc_le / mc_l) * 100:.0f} %)")
        s_model = sky.diffuse_fluxes(fine)[0]
        ratio = np.interp(fine, wl, mc_e / diffuse)
        t_model, t_mc = cct(s_model, fine), cct(s_model * ratio, fine)
        print(f"| {tau:g} | {sun:g} | {' / '.join(f'{100 * v:+.1f}' for v in d_e)} % | "
              f"{' / '.join(f'{100 * v:.1f}' for v in mc_ee / mc_e)} % | {kind} | {rad_text} | "
              f"{t_model:.0f} / {t_mc:.0f} K | {dt:.2f} |", flush=True)
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
