"""Monte Carlo references for the clear sky's light on the cloud top at a low sun (docs/clouds.md, "The sun 10 and
2 deg high: what the remaining misses are").

The cloudy model lights its cloud layer from the top with the precomputed clear sky ([Bruneton2008] Eq. 16, its
radiance at the cloud top). This script stores, for the Earth defaults' air (ground albedo 0.2, the Earth's radius)
at the cloud top 1500 m, 450 / 550 / 650 nm, per sun elevation:

* ``backward``: the clear sky's radiance there from backward paths (:class:`~skyscatter.sky.montecarlo.MonteCarloSky`,
  exact in the spherical atmosphere: no domain), per unit solar irradiance [sr^-1], with its standard error, at
  8 Gauss-Legendre nodes in the cosine of the view zenith on (0, 1) (``mu_nodes``, ``mu_weights``) times 13 azimuths
  0-180 deg from the sun (``azimuths_deg``; the sky is symmetric about the sun's vertical plane). Its hemisphere
  integral ``E = 2 int_0^pi int_0^1 L mu dmu dphi`` (the trapezoid rule in azimuth) is the sky's diffuse irradiance.
* ``forward``: the downward diffuse irradiance at 1500 m from forward photons over the periodic domain
  (:func:`~skyscatter.montecarlo.domain.domain_quantities` with an empty marker field at 0-100 m, as
  ``cloudy_low_sun_reference.py`` runs them), per unit normal solar irradiance, two seeds: the estimator of the
  stored sun-10-deg references under the cloud (``tests/data/cloudy_low_sun.json``), whose periodic domain in a
  sphere is short of diffuse light at a low sun (docs/clouds.md, Forward photons for fluxes).

``nice -n 19 python benchmarks/cloudy_top_sky_reference.py --paths 4000 --photons 65536
--out tests/data/cloudy_top_sky.json`` (deterministic for the seeds; about 10 CPU-min at load 3).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters, DensityProfile
from skyscatter.atmosphere.clouds import CloudField
from skyscatter.atmosphere.particles import AnalyticParticles
from skyscatter.fileio import atomic_path
from skyscatter.montecarlo.domain import domain_quantities
from skyscatter.sky.montecarlo import MonteCarloSky

WAVELENGTHS = [450.0, 550.0, 650.0]
TOP, ALBEDO = 1500.0, 0.2
NODES = 8
AZIMUTHS_DEG = np.arange(0.0, 180.0 + 1e-9, 15.0)


def nodes() -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights in the cosine on (0, 1)."""
    x, w = np.polynomial.legendre.leggauss(NODES)
    return 0.5 * (x + 1.0), 0.5 * w


def directions() -> np.ndarray:
    """Unit view directions (n_mu, n_az, 3), east-north-up, azimuths from the sun (at azimuth 0, north)."""
    mu, _ = nodes()
    t, p = np.meshgrid(np.arccos(mu), np.radians(AZIMUTHS_DEG), indexing="ij")
    return np.stack([np.sin(t) * np.sin(p), np.sin(t) * np.cos(p), np.cos(t)], axis=-1)


def run(sun: float, paths: int, photons: int, seeds: list[int], seed: int) -> dict:
    atm = AtmosphereParameters(ground_albedo=ALBEDO)
    e0 = np.asarray(atm.solar_irradiance_at(WAVELENGTHS))
    sz = math.radians(90.0 - sun)
    t0, c0 = time.perf_counter(), time.process_time()
    mc = MonteCarloSky(sz, 0.0, atmosphere=atm, altitude=TOP, samples=paths, seed=seed)
    rad, err = mc.radiance_and_error(directions(), WAVELENGTHS)
    case = {"sun_elevation_deg": sun,
            "backward": {"seed": seed, "paths_per_direction": paths, "radiance": (rad / e0).tolist(),
                         "radiance_stderr": (err / e0).tolist(), "seconds": time.perf_counter() - t0,
                         "cpu_seconds": time.process_time() - c0},
            "forward": [], "load_average": os.getloadavg()[0]}
    hg = AnalyticParticles("marker", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)
    empty = CloudField(np.zeros((1, 1, 1)), 1000.0, 0.0, 100.0, hg, origin=(0.0, 0.0))
    for s in seeds if photons > 0 else []:
        t0, c0 = time.perf_counter(), time.process_time()
        d = domain_quantities(atm, empty, WAVELENGTHS, sun_zenith=sz, up_views=None, samples=photons, seed=s,
                              levels=[TOP])
        i = int(np.argmin(np.abs(np.asarray(d.levels) - TOP)))
        diffuse = (d.level_down[i] - d.level_direct[i]).mean(axis=(0, 1)) * math.cos(sz)
        case["forward"].append({"seed": s, "photons": int(d.photons), "diffuse_down": diffuse.tolist(),
                                "diffuse_down_stderr": (d.level_down_stderr[i].mean(axis=(0, 1))
                                                        * math.cos(sz)).tolist(),
                                "seconds": time.perf_counter() - t0, "cpu_seconds": time.process_time() - c0})
    return case


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--suns", default="10,2", help="sun elevations [deg]")
    ap.add_argument("--paths", type=int, default=4000, help="backward paths per direction")
    ap.add_argument("--photons", type=int, default=65536, help="forward photons per run (0: none)")
    ap.add_argument("--seeds", default="31,32", help="forward seeds")
    ap.add_argument("--seed", type=int, default=5, help="backward seed")
    ap.add_argument("--out", default="tests/data/cloudy_top_sky.json")
    a = ap.parse_args()
    mu, w = nodes()
    data = {"description": __doc__.splitlines()[0], "wavelengths_nm": WAVELENGTHS, "cloud_top_m": TOP,
            "ground_albedo": ALBEDO, "mu_nodes": mu.tolist(), "mu_weights": w.tolist(),
            "azimuths_deg": AZIMUTHS_DEG.tolist(), "cases": []}
    for sun in (float(s) for s in a.suns.split(",")):
        case = run(sun, a.paths, a.photons, [int(s) for s in a.seeds.split(",")], a.seed)
        data["cases"].append(case)
        with atomic_path(Path(a.out)) as tmp:
            Path(tmp).write_text(json.dumps(data, indent=1))
        rad = np.array(case["backward"]["radiance"])
        e = 2.0 * np.einsum("i,ik->k", mu * w, np.trapezoid(rad, np.radians(AZIMUTHS_DEG), axis=1))
        print(sun, "backward E", np.round(e, 5).tolist(), "forward",
              [np.round(r["diffuse_down"], 5).tolist() for r in case["forward"]], flush=True)


if __name__ == "__main__":
    main()
