"""Forward-photon references for the cloudy sky at a low sun (2 and 10 deg), where the stored backward estimates
of ``cloudy_montecarlo_reference.py`` fail (docs/clouds.md, "The sun 2 and 10 deg high").

Each case: the water cloud 1000-1500 m (Mie r_e 10 um) of optical depth ``tau`` over a ground of albedo 0.2, in
the Earth defaults' air (``earth``) or in an empty one (``vacuum``: Rayleigh 1e-14 of Earth's, no aerosol, no
ozone), on a planet of ``scale`` Earth radii (the air's profile unchanged; 1000: the plane-parallel limit, where
the forward photons' periodic domain is exact to 0.1 %; docs/clouds.md, Forward photons for fluxes). Stored per
case: the ground's diffuse irradiance at 450 / 550 / 650 nm [W m^-2 nm^-1] from forward photons
(:func:`skyscatter.montecarlo.domain.domain_quantities`, an empty 1 km periodic field marking the domain), its
standard error, the photons and seeds (two independent runs; ``--photons 0``: none); optionally (``--backward N``)
the backward cosine-path estimate (:func:`~skyscatter.montecarlo.domain.ground_irradiance`, N paths per run, one
run per seed of ``--backward-seeds``, default the first forward seed + 100) beside it, as the list ``backward``.
At the Earth's radius with the sun 2 deg high only the backward paths are a reference (the forward photons'
periodic domain is 7-34 % off there; their heavy tail: docs/clouds.md, "The sun 2 deg high"), e.g.
``--cases earth:5:2:1 --photons 0 --backward 400000 --backward-seeds 51,52,53``.

``nice python benchmarks/cloudy_low_sun_reference.py --cases earth:1:2:1000,earth:15:2:1000,... --photons 65536
--out tests/data/cloudy_low_sun.json`` (air:tau:sun:scale; a case already in the file gains the runs of the
seeds it lacks, forward and backward; the file is rewritten atomically after each case).
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
from skyscatter.atmosphere.clouds import CloudField, CloudLayer
from skyscatter.atmosphere.particles import AnalyticParticles
from skyscatter.atmosphere.spectra import PowerLawSpectrum
from skyscatter.fileio import atomic_path
from skyscatter.montecarlo.domain import domain_quantities, ground_irradiance

WAVELENGTHS = [450.0, 550.0, 650.0]
BASE, TOP, ALBEDO = 1000.0, 1500.0, 0.2


def clear_air(air: str, scale: float) -> AtmosphereParameters:
    """The air (``earth`` or ``vacuum``) on a planet of ``scale`` Earth radii, ground albedo 0.2."""
    base = AtmosphereParameters()
    kw = {}
    if air == "vacuum":
        kw = dict(rayleigh_scattering=PowerLawSpectrum(1e-14, 1000.0, -4.0, "no Rayleigh"), mie_angstrom_beta=0.0,
                  ozone_column=0.0)
    elif air != "earth":
        raise ValueError(f"air must be earth or vacuum; got {air!r}")
    rb = base.bottom_radius * scale
    return AtmosphereParameters(bottom_radius=rb, top_radius=rb + base.thickness, ground_albedo=ALBEDO, **kw)


def run_case(air: str, tau: float, sun: float, scale: float, photons: int, seeds: list[int], backward: int,
             backward_seeds: list[int]) -> dict:
    clear = clear_air(air, scale)
    atm = clear.replace(particles=(CloudLayer(BASE, TOP, tau),)) if tau > 0 else clear
    sz = math.radians(90.0 - sun)
    hg = AnalyticParticles("marker", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)
    empty = CloudField(np.zeros((1, 1, 1)), 1000.0, 0.0, 100.0, hg, origin=(0.0, 0.0))
    e0 = atm.solar_irradiance_at(WAVELENGTHS) * math.cos(sz)
    runs = []
    for seed in seeds if photons > 0 else []:
        t0, c0 = time.perf_counter(), time.process_time()
        d = domain_quantities(atm, empty, WAVELENGTHS, sun_zenith=sz, up_views=None, samples=photons, seed=seed)
        runs.append({"seed": seed, "photons": int(d.photons),
                     "diffuse_irradiance": ((d.transmittance[0, 0] - d.direct_transmittance[0, 0]) * e0).tolist(),
                     "diffuse_irradiance_stderr": (d.transmittance_stderr[0, 0] * e0).tolist(),
                     "seconds": time.perf_counter() - t0, "cpu_seconds": time.process_time() - c0})
    case = {"air": air, "tau": tau, "sun_elevation_deg": sun, "radius_scale": scale, "forward": runs,
            "load_average": os.getloadavg()[0]}
    if backward:
        case["backward"] = []
        for seed in backward_seeds:
            t0, c0 = time.perf_counter(), time.process_time()
            g = ground_irradiance(atm, WAVELENGTHS, sun_zenith=sz, samples=backward, seed=seed)
            case["backward"].append({"seed": seed, "paths": backward, "diffuse_irradiance": g.diffuse[0].tolist(),
                                     "diffuse_irradiance_stderr": g.diffuse_stderr[0].tolist(),
                                     "seconds": time.perf_counter() - t0, "cpu_seconds": time.process_time() - c0})
            print(f"  backward seed {seed}: {np.round(g.diffuse[0], 5).tolist()} +- "
                  f"{np.round(g.diffuse_stderr[0] / g.diffuse[0], 4).tolist()} rel", flush=True)
    return case


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", required=True, help="air:tau:sun:scale,... (air earth or vacuum)")
    ap.add_argument("--photons", type=int, default=65536)
    ap.add_argument("--seeds", default="21,22")
    ap.add_argument("--backward", type=int, default=0, help="backward paths per run (0: none)")
    ap.add_argument("--backward-seeds", default=None, help="seeds of the backward runs (default: first seed + 100)")
    ap.add_argument("--out", default="tests/data/cloudy_low_sun.json")
    a = ap.parse_args()
    out = Path(a.out)
    data = json.loads(out.read_text()) if out.exists() else {
        "description": __doc__.splitlines()[0], "wavelengths_nm": WAVELENGTHS, "cloud_base_m": BASE,
        "cloud_top_m": TOP, "effective_radius_m": 10e-6, "ground_albedo": ALBEDO, "cases": []}
    seeds = [int(s) for s in a.seeds.split(",")]
    bseeds = [int(s) for s in a.backward_seeds.split(",")] if a.backward_seeds else [seeds[0] + 100]
    for spec in a.cases.split(","):
        air, tau, sun, scale = spec.split(":")
        key = (air, float(tau), float(sun), float(scale))
        old = [c for c in data["cases"] if (c["air"], c["tau"], c["sun_elevation_deg"], c["radius_scale"]) == key]
        # a case already stored gains the runs of the seeds it lacks (each run keeps its seed and count)
        new_seeds = [s for s in seeds if not old or s not in [r["seed"] for r in old[0]["forward"]]]
        new_bseeds = [s for s in bseeds if not old or s not in [r["seed"] for r in old[0].get("backward", [])]]
        photons = a.photons if new_seeds else 0
        backward = a.backward if new_bseeds else 0
        if old and not (photons or backward):
            continue
        case = run_case(air, float(tau), float(sun), float(scale), photons, new_seeds, backward, new_bseeds)
        if old:
            old[0]["forward"] += case["forward"]
            if "backward" in case:
                old[0]["backward"] = old[0].get("backward", []) + case["backward"]
        else:
            data["cases"].append(case)
        with atomic_path(out) as tmp:
            Path(tmp).write_text(json.dumps(data, indent=1))
        print(spec, [np.round(r["diffuse_irradiance"], 5).tolist() for r in case["forward"]],
              [np.round(np.array(r["diffuse_irradiance_stderr"]) / np.array(r["diffuse_irradiance"]), 4).tolist()
               for r in case["forward"]], [r["diffuse_irradiance"] for r in case.get("backward", [])], flush=True)


if __name__ == "__main__":
    main()
