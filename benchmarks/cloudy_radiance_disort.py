"""The cloudy sky's radiance under horizontally uniform cloud layers against plane-parallel DISORT references
(issue 22 item 5: radiance 10 deg or more above the horizon within 5 %; docs/clouds.md, "Radiance under clouds").

The reference is not the model's code: ``tests/disort_reference.py::disort_cloud`` (disortpp, [Stamnes1988]) on
its own layering of the column (100 layers, 20 in the cloud), Rayleigh + the water cloud (1000-1500 m, Mie
droplets r_e 10 um, variance 0.1: the cloud's extinction, albedo and 400 Legendre moments of its phase table),
delta-M with the TMS single-scattering correction of [NakajimaTanaka1988] added explicitly (disortpp 1.2.1's flag
does nothing; without it 32 and 64 streams differ by up to 6 % under optical depth 1, with it by 0.8 % 25 deg or
more from the sun), a Lambertian ground of albedo 0.2, no aerosol and no ozone, the beam from the top
(plane-parallel), at 64 and at 32 streams (the stream convergence). That DISORT setup agrees with the Monte
Carlo's backward paths within 2 % + 3 standard errors on 192 views (docs/clouds.md, Validation); here it
replaces the Monte Carlo, whose radiances under a cloud at a few thousand paths are heavy-tailed.

The model (:class:`skyscatter.sky.cloudy.CloudySky`, its default 16 streams) sees the same air on a planet of
1000 Earth radii (the plane-parallel limit: ``water_cloud_case``'s air without the layer, the model adds its own
``cloud_optical_depth``), in two ways: ``illumination="column"`` (the whole column in DISORT) and the default
``"tables"`` (the column from the cloud top down, lit by the precomputed clear sky). Also stored: the default
model on the Earth's radius (the geometry's share: the sphere against the plane-parallel limit).

Views: elevations 10, 20, 30, 45, 60, 90 deg at azimuths 0, 45, 90, 135, 180 deg from the sun; 450 / 550 / 650
nm; optical depths 1, 5, 15, 30, 60; sun elevations 60, 30, 10, 2 deg. Views within 25 deg of the sun are stored
but flagged (the aureole inside the droplets' diffraction peak: delta-M's radiance there is not a reference).
Deterministic (no random numbers: no seed, no paths).

``nice python benchmarks/cloudy_radiance_disort.py --out tests/data/cloudy_radiance_disort.json`` (atomically
rewritten after each case; ``--cases 15:30,60:10`` for a subset; ``--streams-only`` skips the model).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.fileio import atomic_path
from skyscatter.sky.cloudy import CloudySky

sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
from disort_reference import disort_cloud, water_cloud_case  # noqa: E402

WAVELENGTHS = [450.0, 550.0, 650.0]
ELEVATIONS = [10.0, 20.0, 30.0, 45.0, 60.0, 90.0]
AZIMUTHS = [0.0, 45.0, 90.0, 135.0, 180.0]
TAUS = [1.0, 5.0, 15.0, 30.0, 60.0]
SUNS = [60.0, 30.0, 10.0, 2.0]
ALBEDO = 0.2
BASE, TOP = 1000.0, 1500.0
PLANE_PARALLEL = 1000.0  # Earth radii
AUREOLE_DEG = 25.0


def views() -> list[tuple[float, float]]:
    """(elevation, azimuth from the sun) [deg] of the compared views."""
    return [(h, a) for h in ELEVATIONS for a in (AZIMUTHS if h < 90.0 else [0.0])]


def directions(sun_azimuth_deg: float = 0.0) -> np.ndarray:
    """Unit vectors (x east, y north, z up) of :func:`views` for a sun at ``sun_azimuth_deg``."""
    out = []
    for h, a in views():
        h, a = math.radians(h), math.radians(a + sun_azimuth_deg)
        out.append([math.cos(h) * math.sin(a), math.cos(h) * math.cos(a), math.sin(h)])
    return np.array(out)


def near_sun(sun: float) -> list[bool]:
    """Views within :data:`AUREOLE_DEG` of a sun ``sun`` deg high."""
    s = np.array([0.0, math.cos(math.radians(sun)), math.sin(math.radians(sun))])
    return [bool(v) for v in directions() @ s > math.cos(math.radians(AUREOLE_DEG))]


def air(scale: float) -> AtmosphereParameters:
    """The reference's air without the cloud (Rayleigh, no aerosol, no ozone, albedo 0.2) on ``scale`` Earth
    radii."""
    rb = AtmosphereParameters().bottom_radius * scale
    return water_cloud_case(1.0, True, ALBEDO, rb)[1].replace(particles=())


def reference(tau: float, sun: float, streams: int) -> np.ndarray:
    """DISORT's downward radiance at the ground per unit solar irradiance [sr^-1], (n_views, n_wl)."""
    rb = AtmosphereParameters().bottom_radius * PLANE_PARALLEL
    layer, atm = water_cloud_case(tau, True, ALBEDO, rb)
    sz = math.radians(90.0 - sun)
    out = np.empty((len(views()), len(WAVELENGTHS)))
    elev = sorted(set(h for h, _ in views()))
    for k, wl in enumerate(WAVELENGTHS):  # one solve per wavelength: every elevation x every azimuth
        rad, _ = disort_cloud(atm, layer, wl, sz, np.radians([90.0 - h for h in elev]), np.radians(AZIMUTHS), ALBEDO,
                              n_streams=streams, single_scatter=True)
        for i, (h, a) in enumerate(views()):
            out[i, k] = rad[elev.index(h), AZIMUTHS.index(a)]
    return out


def model(tau: float, sun: float, scale: float, illumination: str) -> tuple[np.ndarray, float]:
    """The cloudy model's radiance per unit solar irradiance [sr^-1] (n_views, n_wl) and its solve time [s]."""
    a = air(scale)
    t0 = time.process_time()
    sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=BASE, cloud_top=TOP,
                    ground_albedo=ALBEDO, atmosphere=a, illumination=illumination)
    rad = sky.spectral_radiance(directions(), WAVELENGTHS) / a.solar_irradiance_at(WAVELENGTHS)[None, :]
    return rad, time.process_time() - t0


def summary(case: dict) -> None:
    """Print a case's largest and median |relative difference| against 64-stream DISORT (views 25 deg or more from
    the sun)."""
    r64 = np.array(case["disort64"])
    far = ~np.array(case["near_sun"])

    def worst(key: str) -> str:
        rel = (np.array(case[key]) / r64 - 1)[far]
        i = np.unravel_index(np.argmax(np.abs(rel)), rel.shape)
        return f"max |rel| {abs(rel[i]):.2%} ({rel[i]:+.2%}), median {np.median(np.abs(rel)):.2%}"

    print(f"tau {case['tau']:4.0f} sun {case['sun_elevation_deg']:4.0f}: 32 vs 64 streams {worst('disort32')}; "
          f"column {worst('model_column_pp')}; tables (pp) {worst('model_tables_pp')}; tables (Earth) "
          f"{worst('model_tables_earth')}", flush=True)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--out", type=Path, default=Path("tests/data/cloudy_radiance_disort.json"))
    p.add_argument("--cases", default="", help="tau:sun,... (default: all 20)")
    p.add_argument("--remodel", action="store_true",
                   help="recompute only the model's values of the stored cases (the DISORT references kept)")
    args = p.parse_args()
    cases = ([tuple(float(v) for v in c.split(":")) for c in args.cases.split(",")] if args.cases
             else [(t, s) for s in SUNS for t in TAUS])
    data = {"description": "Downward radiance at the ground per unit solar irradiance [sr^-1] under a water cloud "
                           "layer (1000-1500 m, Mie r_e 10 um, v_eff 0.1) over Rayleigh air (no aerosol, no ozone), "
                           "ground albedo 0.2, plane-parallel: disortpp (tests/disort_reference.py::disort_cloud, "
                           "100 layers, 400 moments, delta-M + TMS) at 64 and 32 streams; the cloudy model on a "
                           "planet of 1000 Earth radii (column / tables illumination) and on the Earth's radius "
                           "(tables). "
                           "Written by benchmarks/cloudy_radiance_disort.py (deterministic).",
            "wavelengths_nm": WAVELENGTHS, "views_deg": views(), "aureole_deg": AUREOLE_DEG,
            "cloud_base_m": BASE, "cloud_top_m": TOP, "ground_albedo": ALBEDO, "cases": []}
    if args.out.exists():
        data = json.loads(args.out.read_text())
    if args.remodel:
        for case in data["cases"]:
            tau, sun = case["tau"], case["sun_elevation_deg"]
            for key, scale, ill in (("model_column_pp", PLANE_PARALLEL, "column"),
                                    ("model_tables_pp", PLANE_PARALLEL, "tables"),
                                    ("model_tables_earth", 1.0, "tables")):
                vals, t = model(tau, sun, scale, ill)
                case[key] = vals.tolist()
                case["cpu_s"][key] = t
            summary(case)
        with atomic_path(args.out) as tmp:
            Path(tmp).write_text(json.dumps(data, indent=1))
        return
    done = {(c["tau"], c["sun_elevation_deg"]) for c in data["cases"]}
    for tau, sun in cases:
        if (tau, sun) in done:
            continue
        t0 = time.process_time()
        r64 = reference(tau, sun, 64)
        t_ref = time.process_time() - t0
        r32 = reference(tau, sun, 32)
        col, t_col = model(tau, sun, PLANE_PARALLEL, "column")
        tab, t_tab = model(tau, sun, PLANE_PARALLEL, "tables")
        earth, t_earth = model(tau, sun, 1.0, "tables")
        case = {"tau": tau, "sun_elevation_deg": sun, "near_sun": near_sun(sun), "disort64": r64.tolist(),
                "disort32": r32.tolist(), "model_column_pp": col.tolist(), "model_tables_pp": tab.tolist(),
                "model_tables_earth": earth.tolist(),
                "cpu_s": {"disort64": t_ref, "model_column_pp": t_col, "model_tables_pp": t_tab,
                          "model_tables_earth": t_earth}}
        data["cases"].append(case)
        with atomic_path(args.out) as tmp:
            Path(tmp).write_text(json.dumps(data, indent=1))

        summary(case)

if __name__ == "__main__":
    main()
