"""Mitsuba 3 against our Monte Carlo on the same procedural cloud field, at equal standard error
(docs/clouds.md, "Mitsuba timing").

The problem, the same for both: a procedural broken-cloud field (:meth:`CloudField.procedural`, cover 0.6, base 1000
m, highest tops 2500 m, mean optical depth 10 of the cloudy columns, 8 km square open (non-periodic) box at 64 x 64
x 24 voxels, seed 3) of conservative droplets with a Henyey-Greenstein phase function (g = 0.85, single scattering
albedo 1; both renderers sample it exactly, so neither pays for a tabulated peak), in vacuum (no air), over a black
ground, the sun 30 deg from the zenith; the quantity is the radiance reaching the ground at the box's centre from
the zenith, per unit solar irradiance [sr^-1] (550 nm). Our side: :func:`skyscatter.montecarlo.sky_radiance` (delta
tracking against the block majorant grid, next-event estimation to the sun; a planet of 1000 Earth radii so that the
field's spherical boundaries are flat to 1 mm). Mitsuba's: ``scalar_rgb`` (grey: its three channels equal;
``llvm_ad_mono`` crashed in LLVM code generation here), a ``radiancemeter`` at the same point looking up, a
``directional`` emitter, the field as a ``gridvolume`` in a ``heterogeneous`` medium inside a ``cube`` with a
``null`` BSDF, ``volpath`` (unbounded depth), its standard error from the spread of independent renders. Both timed
in CPU seconds of this process (``time.process_time``: the machine is shared), the first (compiling) call excluded;
efficiency = 1 / (variance x CPU time), its ratio = Mitsuba's CPU time to reach our standard error over ours.

``python benchmarks/mitsuba_cloud_timing.py [--paths 20000] [--spp 2000] [--renders 10] [--threads 1]``
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters, DensityProfile
from skyscatter.atmosphere.clouds import CloudField
from skyscatter.atmosphere.particles import AnalyticParticles
from skyscatter.atmosphere.spectra import PowerLawSpectrum
from skyscatter.montecarlo import sky_radiance

SUN_ZENITH = math.radians(30.0)
SIZE, BASE, TOP = 8000.0, 1000.0, 2500.0


def field() -> CloudField:
    drops = AnalyticParticles("drops", DensityProfile.uniform(), PowerLawSpectrum(1.0, 550.0, 0.0, "grey"), 1.0,
                              "henyey-greenstein", 0.85)
    return CloudField.procedural(cover=0.6, base=BASE, top=TOP, particles=drops, optical_depth=10.0,
                                 size=SIZE, resolution=(64, 64, 24), feature_size=2000.0, seed=3,
                                 origin=(-SIZE / 2, -SIZE / 2), periodic=False)


def ours(clouds: CloudField, paths: int, seed: int) -> tuple[float, float, float]:
    """(radiance per unit solar irradiance [sr^-1], its standard error, CPU seconds)."""
    base = AtmosphereParameters()
    rb = base.bottom_radius * 1000.0
    vac = AtmosphereParameters(bottom_radius=rb, top_radius=rb + base.thickness, ground_albedo=0.0,
                               rayleigh_scattering=PowerLawSpectrum(1e-14, 1000.0, -4.0, "no Rayleigh"),
                               mie_angstrom_beta=0.0, ozone_column=0.0)
    e0 = float(vac.solar_irradiance_at([550.0])[0])
    t0, w0 = time.process_time(), time.perf_counter()
    r = sky_radiance(vac, [[0.0, 0.0, 1.0]], [550.0], sun_zenith=SUN_ZENITH, sun_azimuth=0.0, samples=paths,
                     seed=seed, clouds=clouds)
    dt = time.process_time() - t0
    print(f"  (ours: {time.perf_counter() - w0:.1f} s wall)", flush=True)
    return float(r.radiance[0, 0]) / e0, float(r.stderr[0, 0]) / e0, dt


def mitsuba_scene(clouds: CloudField, threads: int):
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    if hasattr(dr, "set_thread_count"):
        dr.set_thread_count(threads)
    ext = np.asarray(clouds.extinction, dtype=np.float32)
    grid = mi.VolumeGrid(np.ascontiguousarray(ext.transpose(2, 1, 0)[..., None]))
    to_world = (mi.ScalarTransform4f().translate([-SIZE / 2, -SIZE / 2, BASE])
                @ mi.ScalarTransform4f().scale([SIZE, SIZE, TOP - BASE]))
    sun = [math.sin(SUN_ZENITH) * math.sin(0.0), math.sin(SUN_ZENITH) * math.cos(0.0), math.cos(SUN_ZENITH)]
    # the cube primitive spans [-1, 1]^3: map it onto the field's box as the grid volume's unit cube is
    cube_to_world = (mi.ScalarTransform4f().translate([0.0, 0.0, 0.5 * (BASE + TOP)])
                     @ mi.ScalarTransform4f().scale([SIZE / 2, SIZE / 2, 0.5 * (TOP - BASE)]))
    return mi, dr, mi.load_dict({
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": -1},
        "sensor": {"type": "radiancemeter", "origin": [0.0, 0.0, 0.01], "direction": [0.0, 0.0, 1.0],
                   "film": {"type": "hdrfilm", "width": 1, "height": 1, "rfilter": {"type": "box"},
                            "pixel_format": "rgb"},
                   "sampler": {"type": "independent"}},
        "sun": {"type": "directional", "direction": [-s for s in sun], "irradiance": 1.0},
        "cloud": {"type": "cube", "to_world": cube_to_world, "bsdf": {"type": "null"},
                  "interior": {"type": "heterogeneous", "albedo": 1.0, "scale": 1.0,
                               "sigma_t": {"type": "gridvolume", "grid": grid, "to_world": to_world,
                                           "filter_type": "nearest"},
                               "phase": {"type": "hg", "g": 0.85}}},
    })


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--paths", type=int, default=20000)
    ap.add_argument("--spp", type=int, default=2000)
    ap.add_argument("--renders", type=int, default=10)
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args()
    clouds = field()
    ext = np.asarray(clouds.extinction)
    print(f"field {ext.shape}, max extinction {ext.max():.4g} m^-1, cloudy columns "
          f"{np.mean(ext.sum(axis=2) > 0):.3f}", flush=True)
    ours(clouds, 256, 1)  # compile
    l_o, e_o, t_o = ours(clouds, a.paths, 2)
    print(f"ours: L = {l_o:.5g} +- {e_o:.3g} sr^-1 ({e_o / l_o:.3%}), {a.paths} paths, {t_o:.1f} CPU s", flush=True)
    mi, dr, scene = mitsuba_scene(clouds, a.threads)
    np.asarray(mi.render(scene, spp=16, seed=0))  # compile
    vals = []
    t0, w0 = time.process_time(), time.perf_counter()
    for k in range(a.renders):
        vals.append(float(np.asarray(mi.render(scene, spp=a.spp, seed=k + 1)).ravel()[0]))
    t_m = time.process_time() - t0
    print(f"  (mitsuba: {time.perf_counter() - w0:.1f} s wall)", flush=True)
    vals = np.array(vals)
    l_m, e_m = vals.mean(), vals.std(ddof=1) / math.sqrt(vals.size)
    print(f"mitsuba: L = {l_m:.5g} +- {e_m:.3g} sr^-1 ({e_m / l_m:.3%}), {a.renders} x {a.spp} spp, "
          f"{t_m:.1f} CPU s", flush=True)
    ratio = (e_m ** 2 * t_m) / (e_o ** 2 * t_o)
    print(f"difference {l_m / l_o - 1:+.2%} ({(l_m - l_o) / math.hypot(e_m, e_o):+.1f} sigma); CPU time to equal "
          f"standard error, Mitsuba / ours: {ratio:.2f}; load average {os.getloadavg()}", flush=True)


if __name__ == "__main__":
    main()
