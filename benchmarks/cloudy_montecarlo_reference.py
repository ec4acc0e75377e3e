"""Monte Carlo reference values under horizontally uniform cloud layers (the stored values the cloudy sky is
measured against: tests/data/cloudy_montecarlo.json, docs/clouds.md "Fast cloud layers").

Each case: Earth defaults (Rayleigh, the default aerosol, ozone, ground albedo 0.2) with a water cloud layer
(:class:`~skyscatter.atmosphere.clouds.CloudLayer`, Mie droplets r_e = 10 um, v_e = 0.1) from 1000 to 1500 m of
optical depth ``tau`` at 550 nm, the sun at elevation ``h``; wavelengths 450, 550, 650 nm (one hero group).
Stored: the diffuse irradiance on the ground by forward photons
(:func:`skyscatter.montecarlo.domain.domain_quantities`, an empty periodic field marking the domain) and the sky
radiance seen from the ground (:func:`skyscatter.montecarlo.sky_radiance`) towards a few directions at least
20 deg from the sun, each with its standard error, the seed and the path counts.

The forward photons' periodic domain is off in a sphere at a low sun (without a cloud, against the backward
estimate: +0.1..+0.9 % at sun 30 deg, -2.4..-3.2 % at 10 deg; under the layers -7..-34 % at 2 deg;
docs/clouds.md), so ``--backward N`` adds the diffuse irradiance by backward cosine-distributed paths
(:func:`skyscatter.montecarlo.domain.ground_irradiance`,
N paths; unbiased, but heavy-tailed under a cloud with the sun high: use it for low suns) as
``diffuse_irradiance_backward``.

``nice python benchmarks/cloudy_montecarlo_reference.py --taus 1,5,15,30,60 --suns 60,30,10,2 --paths 4000
--photons 16000 --out tests/data/cloudy_montecarlo.json`` (cases already in the output file are kept and
skipped: the file is rewritten atomically after each case); ``--backward 20000 --cases 15:2,...`` adds the
backward values to existing cases; ``--merge A.json B.json`` merges runs into ``--out``.
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
from skyscatter.fileio import atomic_path
from skyscatter.montecarlo import sky_radiance
from skyscatter.montecarlo.domain import domain_quantities

WAVELENGTHS = [450.0, 550.0, 650.0]
BASE, TOP, ALBEDO = 1000.0, 1500.0, 0.2
#: (elevation, azimuth relative to the sun) [deg] of the radiance directions
VIEWS = [(90.0, 0.0), (30.0, 180.0), (10.0, 90.0), (60.0, 0.0)]
MIN_SUN_DISTANCE = 20.0


def atmosphere(tau: float) -> AtmosphereParameters:
    return AtmosphereParameters(ground_albedo=ALBEDO, particles=(CloudLayer(BASE, TOP, tau),))


def views_for(sun_elev: float) -> list[tuple[float, float]]:
    out = []
    for h, a in VIEWS:
        c = (math.sin(math.radians(h)) * math.sin(math.radians(sun_elev))
             + math.cos(math.radians(h)) * math.cos(math.radians(sun_elev)) * math.cos(math.radians(a)))
        if c < math.cos(math.radians(MIN_SUN_DISTANCE)):
            out.append((h, a))
    return out


def run_case(tau: float, sun_elev: float, paths: int, photons: int, seed: int) -> dict:
    atm = atmosphere(tau)
    sz = math.radians(90.0 - sun_elev)
    views = views_for(sun_elev)
    dirs = np.array([[math.cos(math.radians(h)) * math.sin(math.radians(a)),
                      math.cos(math.radians(h)) * math.cos(math.radians(a)), math.sin(math.radians(h))]
                     for h, a in views])
    t0 = time.perf_counter()
    mc = sky_radiance(atm, dirs, WAVELENGTHS, sun_zenith=sz, sun_azimuth=0.0, samples=paths, seed=seed)
    t1 = time.perf_counter()
    hg = AnalyticParticles("marker", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)
    empty = CloudField(np.zeros((1, 1, 1)), 1000.0, 0.0, 100.0, hg, origin=(0.0, 0.0))
    d = domain_quantities(atm, empty, WAVELENGTHS, sun_zenith=sz, up_views=None, samples=photons, seed=seed + 1)
    t2 = time.perf_counter()
    e0 = atm.solar_irradiance_at(WAVELENGTHS) * math.cos(sz)
    diffuse = (d.transmittance[0, 0] - d.direct_transmittance[0, 0]) * e0
    diffuse_err = d.transmittance_stderr[0, 0] * e0
    return {"tau": tau, "sun_elevation_deg": sun_elev, "views_deg": [list(v) for v in views],
            "radiance": mc.radiance.tolist(), "radiance_stderr": mc.stderr.tolist(),
            "diffuse_irradiance": diffuse.tolist(), "diffuse_irradiance_stderr": diffuse_err.tolist(),
            "direct_irradiance": (d.direct_transmittance[0, 0] * e0).tolist(),
            "paths": paths, "photons": int(d.photons), "seed": seed, "seconds": [t1 - t0, t2 - t1],
            "load_average": os.getloadavg()[0]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--taus", default="1,5,15,30,60")
    ap.add_argument("--suns", default="60,30,10,2")
    ap.add_argument("--cases", default=None, help="tau:sun,... in this order (instead of --taus x --suns)")
    ap.add_argument("--paths", type=int, default=20000)
    ap.add_argument("--photons", type=int, default=40000)
    ap.add_argument("--seed", type=int, default=2200)
    ap.add_argument("--out", default="tests/data/cloudy_montecarlo.json")
    ap.add_argument("--backward", type=int, default=0, help="backward paths for the diffuse irradiance")
    ap.add_argument("--merge", nargs="*", default=None, help="run files to merge into --out")
    a = ap.parse_args()
    out = Path(a.out)
    if a.merge:
        runs = [json.loads(Path(f).read_text()) for f in a.merge]
        merged = {**runs[0], "cases": []}
        for run in runs:
            for case in run["cases"]:
                old = [c for c in merged["cases"] if (c["tau"], c["sun_elevation_deg"])
                       == (case["tau"], case["sun_elevation_deg"])]
                if old:
                    old[0].update({k: v for k, v in case.items() if k.endswith("_backward") or k not in old[0]})
                else:
                    merged["cases"].append(case)
        with atomic_path(out) as tmp:
            Path(tmp).write_text(json.dumps(merged, indent=1))
        return
    data = json.loads(out.read_text()) if out.exists() else {
        "description": __doc__.splitlines()[0], "wavelengths_nm": WAVELENGTHS, "cloud_base_m": BASE,
        "cloud_top_m": TOP, "effective_radius_m": 10e-6, "ground_albedo": ALBEDO, "sun_azimuth_deg": 0.0,
        "atmosphere": "AtmosphereParameters(ground_albedo=0.2) defaults", "cases": []}
    done = {(c["tau"], c["sun_elevation_deg"]) for c in data["cases"]}
    if a.cases:
        todo = [tuple(float(x) for x in c.split(":")) for c in a.cases.split(",")]
    else:
        todo = [(float(t), float(s)) for s in a.suns.split(",") for t in a.taus.split(",")]
    if a.backward:
        from skyscatter.montecarlo.domain import ground_irradiance

        for tau, sun in todo:
            t0 = time.perf_counter()
            g = ground_irradiance(atmosphere(tau), WAVELENGTHS, sun_zenith=math.radians(90.0 - sun),
                                  samples=a.backward, seed=a.seed + 7)
            case = {"tau": tau, "sun_elevation_deg": sun, "diffuse_irradiance_backward": g.diffuse[0].tolist(),
                    "diffuse_irradiance_backward_stderr": g.diffuse_stderr[0].tolist(),
                    "backward_paths": a.backward, "backward_seed": a.seed + 7,
                    "backward_seconds": time.perf_counter() - t0, "backward_load_average": os.getloadavg()[0]}
            old = [c for c in data["cases"] if (c["tau"], c["sun_elevation_deg"]) == (tau, sun)]
            if old:
                old[0].update(case)
            else:
                data["cases"].append(case)
            with atomic_path(out) as tmp:
                Path(tmp).write_text(json.dumps(data, indent=1))
            print(f"tau {tau:g} sun {sun:g}: backward diffuse {np.round(g.diffuse[0], 5)} +- "
                  f"{np.round(g.diffuse_stderr[0], 5)}", flush=True)
        return
    for tau, sun in todo:
        if (tau, sun) in done:
            continue
        case = run_case(tau, sun, a.paths, a.photons, a.seed)
        data["cases"].append(case)
        with atomic_path(out) as tmp:
            Path(tmp).write_text(json.dumps(data, indent=1))
        rel = np.array(case["radiance_stderr"]) / np.array(case["radiance"])
        print(f"tau {tau:g} sun {sun:g}: diffuse {np.round(case['diffuse_irradiance'], 4)} +- "
              f"{np.round(np.array(case['diffuse_irradiance_stderr']) / np.array(case['diffuse_irradiance']), 4)}"
              f" rel; radiance median rel stderr {np.median(rel):.3f}; {case['seconds']} s; "
              f"load {case['load_average']:.1f}", flush=True)


if __name__ == "__main__":
    main()
