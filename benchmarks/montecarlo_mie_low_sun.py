"""Monte Carlo reference for the precomputed tables with a tabulated Mie aerosol at a low sun (issue 20, "Checks":
tables vs the Monte Carlo within 3 % for view zenith <= 70 deg; docs/aerosols.md).

OPAC continental-average and maritime-clean (Hess et al. 1998) at aerosol optical depth 0.2 (550 nm), relative
humidity 50 %, ozone-free, ground albedo 0.1, unit solar irradiance, sun zenith 70 deg (``--sun-zenith``);
radiance at the ground at 550 nm in the principal plane, view zenith 0-70 deg on both sides (not within 5 deg of
the sun), as benchmarks/compare_montecarlo_mie.py does at sun 30 deg. The Monte Carlo
(:func:`skyscatter.montecarlo.sky_radiance`, the full phase table sampled, never truncated) runs ``--paths`` per
direction with a fixed seed per air; the values, their standard errors, the seeds and the path counts go to
``--out`` (tests/data/montecarlo_mie_low_sun.json), which tests/test_precomputed_mie.py holds the tables against.

    nice PYTHONPATH=src python benchmarks/montecarlo_mie_low_sun.py --out tests/data/montecarlo_mie_low_sun.json
    PYTHONPATH=src python benchmarks/montecarlo_mie_low_sun.py --compare tests/data/montecarlo_mie_low_sun.json

``--compare FILE`` runs no Monte Carlo: it prints the tables (the DISORT tests' sizes, 6 orders; ``--sizes`` a JSON
object of size fields to change) / the stored values - 1 [%] and the stored standard errors.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.montecarlo import sky_radiance

TYPES = ("continental-average", "maritime-clean")
SEEDS = {"continental-average": 701, "maritime-clean": 702}


def views(sun_zenith_deg: float) -> list[tuple[float, float]]:
    """(view zenith [deg], side: +1 towards the sun, -1 away) in the principal plane, the sun's 5 deg left out."""
    return [(vz, side) for side in (1.0, -1.0) for vz in np.arange(0.0, 71.0, 10.0)
            if abs(side * vz - sun_zenith_deg) > 5.0]


def air(name: str) -> AtmosphereParameters:
    """The air of the comparison: ``name`` at optical depth 0.2, RH 50 %, ozone-free, albedo 0.1, unit sun [-]."""
    return AtmosphereParameters.with_aerosol_type(name, 0.2, 50.0, ozone_column=0.0, ground_albedo=0.1,
                                                  solar_irradiance=1.0)


def compare(path: Path, extra: dict) -> None:
    """Print the tables / the stored Monte Carlo values of ``path`` - 1 [%] per air and side."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from disort_reference import TABLE_SIZES
    from skyscatter.precomputed import PrecomputedAtmosphere

    data = json.loads(path.read_text())
    ts = math.radians(data["sun_zenith_deg"])
    v = np.array(data["views"])
    vz, side = np.radians(v[:, 0]), v[:, 1]
    d = np.stack([side * np.sin(vz), 0 * vz, np.cos(vz)], axis=-1)
    for case in data["cases"]:
        atm = PrecomputedAtmosphere.compute(air(case["type"]), orders=6, wavelengths=[550.0],
                                            sizes=dict(TABLE_SIZES, **extra), progress=False)
        ours = atm.sky_radiance([0.0, 0.0, atm.parameters.bottom_radius], d, [math.sin(ts), 0.0, math.cos(ts)])[:, 0]
        err = 100 * (ours / np.array(case["radiance"]) - 1)
        se = 100 * np.array(case["relative_stderr"])
        for s, label in ((1.0, "towards sun"), (-1.0, "away")):
            k = side == s
            cells = " ".join(f"{vv:.0f}:{e:+.1f}" for vv, e in zip(v[k, 0], err[k], strict=True))
            print(f"| {case['type']} | {label} | {cells} | {se[k].max():.2f} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sun-zenith", type=float, default=70.0, help="[deg]")
    ap.add_argument("--paths", type=int, default=65536, help="per direction")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--compare", type=Path, default=None)
    ap.add_argument("--sizes", default="{}")
    args = ap.parse_args()
    if args.compare:
        compare(args.compare, json.loads(args.sizes))
        return
    ts = math.radians(args.sun_zenith)
    vs = views(args.sun_zenith)
    vz = np.radians([v[0] for v in vs])
    side = np.array([v[1] for v in vs])
    # ENU directions with the sun at azimuth 90 deg (east, +x), the tables' sun vector
    d = np.stack([side * np.sin(vz), 0 * vz, np.cos(vz)], axis=-1)
    out = {"description": "Monte Carlo sky radiance at the ground, 550 nm, principal plane, with a tabulated Mie "
                          "aerosol at a low sun (skyscatter.montecarlo.sky_radiance, full phase table): the stored "
                          "values tests/test_precomputed_mie.py holds the precomputed tables against",
           "generator": "benchmarks/montecarlo_mie_low_sun.py",
           "air": "AtmosphereParameters.with_aerosol_type(type, 0.2, 50.0, ozone_column=0.0, ground_albedo=0.1, "
                  "solar_irradiance=1.0)",
           "wavelength_nm": 550.0, "sun_zenith_deg": args.sun_zenith, "sun_azimuth_deg": 90.0,
           "views": [[float(v[0]), float(v[1])] for v in vs],
           "views_note": "(view zenith [deg], +1 towards the sun / -1 away); direction (side sin vz, 0, cos vz) ENU",
           "cases": []}
    for name in TYPES:
        t = time.process_time()
        mc = sky_radiance(air(name), d, [550.0], sun_zenith=ts, sun_azimuth=math.pi / 2, samples=args.paths,
                          seed=SEEDS[name])
        cpu = time.process_time() - t
        print(f"{name}: {mc.samples} paths per direction, CPU {cpu:.0f} s; stderr max "
              f"{100 * np.max(mc.relative_stderr):.2f} %", flush=True)
        out["cases"].append({"type": name, "aod_550": 0.2, "relative_humidity": 50.0, "seed": SEEDS[name],
                             "paths": int(mc.samples), "radiance": [float(x) for x in mc.radiance[:, 0]],
                             "relative_stderr": [float(x) for x in mc.relative_stderr[:, 0]],
                             "cpu_s": round(cpu, 1)})
    if args.out:
        args.out.write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
