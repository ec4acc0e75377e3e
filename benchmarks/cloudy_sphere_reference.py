"""Forward-photon references for the cloudy sky in the true spherical atmosphere (the sun 2 deg high and others).

Each case: the water cloud 1000-1500 m (Mie r_e 10 um) of optical depth ``tau`` over a ground of albedo 0.2 in the
Earth defaults' air, at the Earth's radius; the sun ``sun`` deg high. Photons from the sun through the whole
sphere (:func:`skyscatter.montecarlo.sphere.sphere_ground_fluxes`, one wavelength at a time, the default launch
annulus with a 3 deg margin), tallied in rings of local sun elevation 0.5 deg wide centred on ``sun`` and on ``sun
-+ 0.5`` deg (the two neighbours bound the ring's width as a bias: the mean over a ring against its centre differs
by ``(de)^2 / 24 E''/E``). Stored per case and wavelength (450 / 550 / 650 nm): the diffuse and direct irradiance
[W m^-2 nm^-1] and standard errors of the three rings, the radiance [W m^-2 sr^-1 nm^-1] in bins of view zenith
(``ZENITH_EDGES_DEG``) and azimuth from the sun's vertical plane (``AZIMUTH_BINS`` over 0-180 deg) of the centre
ring, the photons, seed, CPU seconds (process time) and the load average.

``nice -n 19 python benchmarks/cloudy_sphere_reference.py --cases 15:2,30:2 --photons 2000000 --seed 1
--out tests/data/cloudy_sphere_forward.json`` (a run of the same case and seed already in the file is replaced;
runs of other seeds are kept, to be pooled; written atomically after each case; ``--zenith-edges`` and
``--azimuth-bins`` choose the radiance's bins).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.atmosphere.clouds import CloudLayer
from skyscatter.fileio import atomic_path
from skyscatter.montecarlo.sphere import sphere_ground_fluxes

WAVELENGTHS = [450.0, 550.0, 650.0]
BASE, TOP, ALBEDO = 1000.0, 1500.0, 0.2
ZENITH_EDGES_DEG = [0.0, 10.0, 35.0, 45.0, 70.0, 80.0]
AZIMUTH_BINS = 4
RING_HALF_DEG = 0.25


def atmosphere(tau: float) -> AtmosphereParameters:
    clear = AtmosphereParameters(ground_albedo=ALBEDO)
    return clear.replace(particles=(CloudLayer(BASE, TOP, tau),)) if tau > 0 else clear


def run_case(tau: float, sun: float, photons: int, seed: int, zenith_edges: list[float], azimuth_bins: int,
             wavelengths: list[float]) -> dict:
    edges = np.radians([sun - 3 * RING_HALF_DEG, sun - RING_HALF_DEG, sun + RING_HALF_DEG, sun + 3 * RING_HALF_DEG])
    out: dict = {"tau": tau, "sun_elevation_deg": sun, "photons": photons, "seed": seed,
                 "ring_edges_deg": np.degrees(edges).tolist(), "view_zenith_edges_deg": zenith_edges,
                 "azimuth_bins": azimuth_bins, "wavelengths_nm": wavelengths, "runs": []}
    for k, w in enumerate(wavelengths):
        c0 = time.process_time()
        r = sphere_ground_fluxes(atmosphere(tau), [w], elevation_edges=edges, photons=photons, seed=seed + 1000 * k,
                                 view_zenith_edges=np.radians(zenith_edges), azimuth_bins=azimuth_bins)
        cpu = time.process_time() - c0
        out["runs"].append({
            "wavelength_nm": w, "seed": seed + 1000 * k, "photons": r.photons,
            "diffuse_irradiance": r.diffuse[:, 0].tolist(),
            "diffuse_irradiance_stderr": r.diffuse_stderr[:, 0].tolist(),
            "direct_irradiance": r.direct[:, 0].tolist(), "direct_irradiance_stderr": r.direct_stderr[:, 0].tolist(),
            "radiance": r.radiance[1, :, :, 0].tolist(), "radiance_stderr": r.radiance_stderr[1, :, :, 0].tolist(),
            "launch_m": r.launch.tolist(), "mean_vertices": r.mean_vertices, "cpu_seconds": cpu,
            "load_average": os.getloadavg()[0]})
        print(f"tau {tau:g} sun {sun:g} {w:g} nm: diffuse {r.diffuse[1, 0]:.6g} +- "
              f"{100 * r.diffuse_stderr[1, 0] / r.diffuse[1, 0]:.2f} % ({r.diffuse[0, 0]:.6g}, {r.diffuse[2, 0]:.6g}),"
              f" {cpu:.0f} CPU-s, load {os.getloadavg()[0]:.1f}", flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", required=True, help="tau:sun,... e.g. 15:2,30:2")
    ap.add_argument("--photons", type=int, default=2_000_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--wavelengths", default=",".join(f"{w:g}" for w in WAVELENGTHS))
    ap.add_argument("--zenith-edges", default=",".join(f"{v:g}" for v in ZENITH_EDGES_DEG),
                    help="view zenith bin edges [deg] of the radiance")
    ap.add_argument("--azimuth-bins", type=int, default=AZIMUTH_BINS)
    ap.add_argument("--out", default=str(Path(__file__).parents[1] / "tests" / "data" / "cloudy_sphere_forward.json"))
    a = ap.parse_args()
    out = Path(a.out)
    data = json.loads(out.read_text()) if out.exists() else {
        "description": __doc__.splitlines()[0], "cloud_base_m": BASE, "cloud_top_m": TOP, "effective_radius_m": 1e-5,
        "ground_albedo": ALBEDO, "cases": []}
    wl = [float(w) for w in a.wavelengths.split(",")]
    for spec in a.cases.split(","):
        tau, sun = (float(v) for v in spec.split(":"))
        case = run_case(tau, sun, a.photons, a.seed, [float(v) for v in a.zenith_edges.split(",")], a.azimuth_bins,
                        wl)
        key = (tau, sun, a.seed)
        data["cases"] = [c for c in data["cases"] if (c["tau"], c["sun_elevation_deg"], c["seed"]) != key] + [case]
        data["cases"].sort(key=lambda c: (-c["sun_elevation_deg"], c["tau"], c["seed"]))
        with atomic_path(out) as tmp:
            Path(tmp).write_text(json.dumps(data, indent=1) + "\n")


if __name__ == "__main__":
    main()
