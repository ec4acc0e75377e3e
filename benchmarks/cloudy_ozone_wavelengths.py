"""Why ``CloudySky`` is 3-4 % low at 550 nm (and not at 450 / 650 nm) under a low sun: the wavelength sampling of ozone.

The ozone cross-section (``AtmosphereParameters.ozone_absorption_at``, Chappuis band) is tabulated with kinks a few
nm apart (a node at 550 nm lies 5 % below the straight line between 540 and 560 nm; one at 575 nm above the line
between 560 and 580 nm). Two linear interpolations in wavelength step over them: the coupling tables
(``COUPLING_TABLE_SIZES``, the 16 default wavelengths 400-700 nm every 20 nm, ``tables.resample``) and the model's
radiance grid (``GRID_WAVELENGTHS``, 380-780 nm every 25 nm). Each interpolates a quantity that holds ``exp(-tau_oz
m)``; with the sun 2 deg high the ozone's air mass ``m`` is about 11 (Beer-Lambert along the sun's ray through the
layer at 22 km), so a 5 % error in ``tau_oz`` (0.028 at 550 nm) is 1.5 % or more of the light (docs/clouds.md).

Measured here (Earth defaults' air, ground albedo 0.2, water cloud 1000-1500 m; forward photons through the sphere,
:func:`skyscatter.montecarlo.sphere.sphere_ground_fluxes`, ring 1.75-2.25 deg, nice 19):

1. clear air at sun 2 deg, 8 wavelengths 450-650 nm: the tables' horizontal sky irradiance on the ground read at the
   16 default wavelengths and resampled, and from tables made at the wavelength itself;
2. optical depth 5 at sun 2 deg, 500 / 575 / 600 nm (beside the stored 450 / 550 / 650 nm references);
3. ``CloudySky`` as it is and with both the coupling tables and ``GRID_WAVELENGTHS`` at 400-700 nm every 25 nm and
   every 10 nm (450 / 550 / 650 nm on the grid; module globals replaced for the measurement only), against the
   stored references (``tests/data/cloudy_sphere_forward.json``, pooled as ``compare_cloudy_sphere.py`` does).

``nice -n 19 python benchmarks/cloudy_ozone_wavelengths.py [--photons 4000000] [--json out.json]`` (some 4 CPU-min at
the defaults; the tables at other wavelengths are computed once and cached).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from pathlib import Path

import numpy as np

import skyscatter.precomputed.cache as table_cache
import skyscatter.sky.cloudy as cloudy
from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.atmosphere.clouds import CloudLayer
from skyscatter.montecarlo.sphere import sphere_ground_fluxes

HERE = Path(__file__).parents[1]
sys.path.insert(0, str(HERE / "tests"))
import cloudy_cct_reference as ref_mod  # noqa: E402

SUN = 2.0
CLEAR_WAVELENGTHS = [450.0, 500.0, 525.0, 550.0, 575.0, 600.0, 625.0, 650.0]
SCAN_WAVELENGTHS = [500.0, 575.0, 600.0]
CASES = [(1.0, 2.0), (5.0, 2.0), (15.0, 2.0), (30.0, 2.0), (60.0, 2.0), (1.0, 10.0), (15.0, 10.0)]


def atmosphere(tau: float) -> AtmosphereParameters:
    clear = AtmosphereParameters(ground_albedo=0.2)
    return clear.replace(particles=(CloudLayer(1000.0, 1500.0, tau),)) if tau > 0 else clear


def photons(tau: float, wl: list[float], n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Diffuse irradiance on the ground [W m^-2 nm^-1] of the ring about ``SUN`` and its standard error, (n_wl,)."""
    edges = np.radians([SUN - 0.75, SUN - 0.25, SUN + 0.25, SUN + 0.75])
    d, e = [], []
    for k, w in enumerate(wl):
        r = sphere_ground_fluxes(atmosphere(tau), [w], elevation_edges=edges, photons=n, seed=seed + 1000 * k)
        d.append(r.diffuse[1, 0])
        e.append(r.diffuse_stderr[1, 0])
        print(f"  photons tau {tau:g} {w:g} nm: {r.diffuse[1, 0]:.6g} +- {100 * e[-1] / d[-1]:.2f} % "
              f"({r.cpu_seconds:.0f} CPU-s)", flush=True)
    return np.array(d), np.array(e)


def stored(tau: float, sun: float, wl: list[float]) -> np.ndarray:
    data = json.loads((HERE / "tests" / "data" / "cloudy_sphere_forward.json").read_text())
    sets = [c for c in data["cases"] if (c["tau"], c["sun_elevation_deg"]) == (tau, sun)]
    return np.array([ref_mod.pooled([(np.array(r["diffuse_irradiance"]), np.array(r["diffuse_irradiance_stderr"]),
                                      r["photons"]) for c in sets for r in c["runs"] if r["wavelength_nm"] == w])[0][1]
                     for w in wl])


def model(tau: float, sun: float, wl: list[float]) -> np.ndarray:
    sky = cloudy.CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau, cloud_base=1000.0,
                           cloud_top=1500.0, ground_albedo=0.2)
    return sky.diffuse_fluxes(wl)[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--photons", type=int, default=4_000_000)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    out: dict = {}
    sz = math.radians(90.0 - SUN)
    clear = atmosphere(0.0)

    print("1. clear air, sun 2 deg: the tables' sky irradiance on the ground against the photons")
    mc, mce = photons(0.0, CLEAR_WAVELENGTHS, a.photons, a.seed)
    t20 = table_cache.cached_atmosphere(clear, sizes=cloudy.COUPLING_TABLE_SIZES, progress=False)
    h20 = t20.resample(t20.horizontal_sky_irradiance([sz]), CLEAR_WAVELENGTHS)[0]
    tat = table_cache.cached_atmosphere(clear, sizes=cloudy.COUPLING_TABLE_SIZES, wavelengths=CLEAR_WAVELENGTHS,
                                        progress=False)
    hat = tat.horizontal_sky_irradiance([sz])[0]
    out["clear"] = {"wavelengths": CLEAR_WAVELENGTHS, "mc": mc.tolist(), "mc_stderr": mce.tolist(),
                    "tables_resampled": (h20 / mc - 1).tolist(), "tables_at_wavelength": (hat / mc - 1).tolist()}
    print("| nm | photons' error | tables at 20 nm, resampled | tables at the wavelength |")
    for i, w in enumerate(CLEAR_WAVELENGTHS):
        print(f"| {w:g} | {100 * mce[i] / mc[i]:.2f} % | {100 * (h20[i] / mc[i] - 1):+.2f} % | "
              f"{100 * (hat[i] / mc[i] - 1):+.2f} % |")

    print("2. optical depth 5, sun 2 deg, between the stored wavelengths")
    s5, s5e = photons(5.0, SCAN_WAVELENGTHS, a.photons // 2, a.seed + 100)
    out["scan_tau5"] = {"wavelengths": SCAN_WAVELENGTHS, "mc": s5.tolist(), "mc_stderr": s5e.tolist()}

    print("3. CloudySky against the photons (450 / 550 / 650 nm; tau 5 also at 500 / 575 / 600 nm)")
    wl = [450.0, 550.0, 650.0]
    refs = {case: stored(*case, wl) for case in CASES}
    orig_cache, orig_grid = table_cache.cached_atmosphere, cloudy.GRID_WAVELENGTHS
    rows = {}
    for label, grid in (("as it is", None), ("tables + grid every 25 nm from 400", np.arange(400.0, 701.0, 25.0)),
                        ("tables + grid every 10 nm from 400", np.arange(400.0, 701.0, 10.0))):
        if grid is not None:
            def at_grid(atm, _g=grid, **kw):
                return orig_cache(atm, wavelengths=_g, **kw)
            table_cache.cached_atmosphere = at_grid
            cloudy.GRID_WAVELENGTHS = grid
        try:
            diffs = {f"{t:g}@{s:g}": (model(t, s, wl) / refs[(t, s)] - 1).tolist() for t, s in CASES}
            diffs["5@2 scan"] = (model(5.0, 2.0, SCAN_WAVELENGTHS) / s5 - 1).tolist()
        finally:
            table_cache.cached_atmosphere, cloudy.GRID_WAVELENGTHS = orig_cache, orig_grid
        rows[label] = diffs
        print(f"{label}: " + " | ".join(f"{k} " + " / ".join(f"{100 * v:+.1f}" for v in d)
                                        for k, d in diffs.items()), flush=True)
    out["model"] = rows
    print(f"load average {os.getloadavg()}")
    if a.json:
        Path(a.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
