"""Monte Carlo reference values of the sky at low sun (the stored values the precomputed tables are held against:
tests/data/low_sun_montecarlo.json, tests/test_precomputed_low_sun.py, docs/accuracy.md "Low sun").

Three atmospheres (Earth defaults; turbidity 3, :meth:`AtmosphereParameters.from_turbidity`; aerosol optical
depth 0.5 at 550 nm, :meth:`AtmosphereParameters.from_aerosol_optical_depth`), sun elevations +10, +3, 0, -3,
-6, -2.3 and -5.1 deg at azimuth 0, an observer on the ground, view elevations 2, 5 and 15 deg at azimuths 0, 45,
90, 135 and 180 deg from the sun, the 16 default table wavelengths (400-700 nm every 20 nm, one hero group per path):
:func:`skyscatter.montecarlo.sky_radiance` with the seed and path count stored per case.

``nice python benchmarks/low_sun_montecarlo_reference.py --out tests/data/low_sun_montecarlo.json`` (cases
already in the output file are kept and skipped: the file is rewritten atomically after each case; ``--paths``
sets the paths per direction with the sun up, twice that at -3 and -2.3 deg and eight times at -5.1 and -6 deg).
With ``--pool`` a case already in the file is not skipped: a new independent run (its own seed, ``--seed`` plus
its place in :data:`CASE_ORDER`) is pooled with the stored values (:func:`pool_runs`: the mean over all the paths
and its standard error); the case keeps its first seed and lists the later runs in ``pooled_runs``.

The Earth's -6 deg case was pooled on 2026-12-06 with ``--atmospheres earth --suns=-6 --paths 3145728 --seed 600
--pool`` (25165824 more paths, seed 615, 1782 s on the shared 2 cores niced beside other work: 33554432 paths per
direction, standard errors median 1.0 -> 0.5 %, largest 3.6 -> 1.8 %), and the optical depth 0.5 one with
``--atmospheres aod05 --suns=-6 --paths 2097152 --seed 600 --pool`` (16777216 more, seed 605, 1604 s: 25165824 per
direction, standard errors median 2.0 -> 1.1 %, largest 4.8 -> 2.7 %).

The cases at -2.3 and -5.1 deg (:data:`MID_SUNS`, added 2026-12-04) were made with ``--paths 262144 --seed 100``
(524288 and 2097152 paths per direction; 216-1127 s each on the shared machine at load 5-9).
The -6 deg cases were made again on 2026-12-06 with ``--suns=-6 --paths 1048576 --seed 300`` (8388608 paths per
direction; 289-974 s each) into a new file and put in place of the earlier ones (1048576 paths, seeds 105, 110,
115). The same day every other case was made again the same way, so that each has at least 1048576 paths per
direction: ``--suns=-5.1,-3 --paths 1048576 --seed 400`` (8388608 and 2097152 paths, 4 and 8 times as many as
before; seeds 417-421, 404-414; 303-439 s and 68-104 s each, niced, on the shared 2 cores), ``--suns=-2.3,0
--paths 1048576 --seed 500`` (2097152 and 1048576 paths, 4 and 8 times; seeds 516-520, 503-513; 40-78 s each) and
``--suns=3,10 --paths 1048576 --seed 500`` (1048576 paths, 8 times; seeds 501-512; 41-68 s each): standard errors
median 0.06-1.1 % (were 0.16-2.2 %); the earlier values lie within the errors of the new (|difference| / combined
standard error median 0.44-0.92 per case, at most 3.16 of 480 values).

Each case has its own random stream, seed ``--seed`` plus its place in :data:`CASE_ORDER` (since 2026-12-03, with
131072 paths: the values stored before used seed 1 in every case and 32768 paths, so a direction's draw repeated at
every sun; in the hazy cells the backward estimate's heavy tail left them 4-8 % low with standard errors too small
to show it, found by reruns at 262144 paths with two other seeds, docs/accuracy.md "Low sun").
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.fileio import atomic_path
from skyscatter.montecarlo import sky_radiance

DESCRIPTION = ("Monte Carlo sky radiance at low sun seen from the ground (skyscatter.montecarlo.sky_radiance), the "
               "stored values the precomputed tables are held against (tests/test_precomputed_low_sun.py)")
WAVELENGTHS = [float(w) for w in range(400, 701, 20)]
SUNS = [10.0, 3.0, 0.0, -3.0, -6.0]
#: Sun elevations [deg] between two sun-zenith texels of the default tables (-2.95 / -1.66 and -5.88 / -4.34 deg),
#: where the lookups read between texels below the horizon (the suns of :data:`SUNS` below it sit within 0.12 deg of a
#: texel): added 2026-12-04.
MID_SUNS = [-2.3, -5.1]
ELEVATIONS = [2.0, 5.0, 15.0]
AZIMUTHS = [0.0, 45.0, 90.0, 135.0, 180.0]
ATMOSPHERES = {
    "earth": ("AtmosphereParameters()", AtmosphereParameters),
    "turbidity3": ("AtmosphereParameters.from_turbidity(3.0)", lambda: AtmosphereParameters.from_turbidity(3.0)),
    "aod05": ("AtmosphereParameters.from_aerosol_optical_depth(0.5)",
              lambda: AtmosphereParameters.from_aerosol_optical_depth(0.5)),
}


def views() -> list[tuple[float, float]]:
    """(elevation, azimuth from the sun) [deg] of the stored directions."""
    return [(e, a) for a in AZIMUTHS for e in ELEVATIONS]


def directions(sun_azimuth_deg: float = 0.0) -> np.ndarray:
    """Unit ENU view directions of :func:`views` (azimuth from north towards east, sun at ``sun_azimuth_deg``)."""
    out = []
    for e, a in views():
        er, ar = math.radians(e), math.radians(a + sun_azimuth_deg)
        out.append([math.cos(er) * math.sin(ar), math.cos(er) * math.cos(ar), math.sin(er)])
    return np.array(out)


#: The order in which the cases take their seeds (``--seed`` + 1 + the case's index).
CASE_ORDER = ([(a, s) for a in ("aod05", "turbidity3", "earth") for s in SUNS]
              + [(a, s) for a in ("aod05", "turbidity3", "earth") for s in MID_SUNS])


def paths_for(sun_elev: float, paths: int) -> int:
    """Paths per direction: below the horizon most collisions are in the planet's shadow (docs/accuracy.md)."""
    if sun_elev <= -4.5:
        return 8 * paths
    if sun_elev < 0.0:
        return 2 * paths
    return paths


def run_case(name: str, sun_elev: float, paths: int, seed: int) -> dict:
    atm = ATMOSPHERES[name][1]()
    n = paths_for(sun_elev, paths)
    t0 = time.perf_counter()
    mc = sky_radiance(atm, directions(), WAVELENGTHS, sun_zenith=math.radians(90.0 - sun_elev), sun_azimuth=0.0,
                      samples=n, seed=seed)
    return {"atmosphere": name, "sun_elevation_deg": sun_elev, "paths": int(mc.samples), "seed": seed,
            "radiance": mc.radiance.tolist(), "radiance_stderr": mc.stderr.tolist(),
            "seconds": round(time.perf_counter() - t0, 1)}


def check_new_seed(stored: dict, seed: int) -> None:
    """Raise ValueError if ``seed`` already made a run of the stored case (pooling needs an independent stream)."""
    if seed == stored["seed"] or seed in {r["seed"] for r in stored.get("pooled_runs", [])}:
        raise ValueError(f"seed {seed} was already used for this case: pooling needs an independent stream")


def pool_runs(stored: dict, new: dict) -> dict:
    """One case from two independent runs of the same estimator (different seeds): the mean over all their paths,
    ``(n1 m1 + n2 m2) / (n1 + n2)``, and its standard error ``sqrt(n1^2 s1^2 + n2^2 s2^2) / (n1 + n2)`` (the runs'
    standard errors of the mean ``s1``, ``s2``). ``seed`` stays the first run's; every later run is listed in
    ``pooled_runs`` with its seed, paths and seconds."""
    check_new_seed(stored, new["seed"])
    n1, n2 = stored["paths"], new["paths"]
    m1, m2 = np.array(stored["radiance"]), np.array(new["radiance"])
    s1, s2 = np.array(stored["radiance_stderr"]), np.array(new["radiance_stderr"])
    out = dict(stored)
    out["paths"] = n1 + n2
    out["radiance"] = ((n1 * m1 + n2 * m2) / (n1 + n2)).tolist()
    out["radiance_stderr"] = (np.sqrt((n1 * s1) ** 2 + (n2 * s2) ** 2) / (n1 + n2)).tolist()
    out["pooled_runs"] = [*stored.get("pooled_runs", []),
                          {"seed": new["seed"], "paths": n2, "seconds": new["seconds"]}]
    out["seconds"] = round(stored["seconds"] + new["seconds"], 1)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("tests/data/low_sun_montecarlo.json"))
    ap.add_argument("--paths", type=int, default=131072, help="paths per direction with the sun up (default 131072)")
    ap.add_argument("--seed", type=int, default=100, help="base seed: a case's is this + 1 + its place in CASE_ORDER")
    ap.add_argument("--atmospheres", default=",".join(ATMOSPHERES))
    ap.add_argument("--suns", default=",".join(f"{s:g}" for s in SUNS + MID_SUNS), help="sun elevations [deg]")
    ap.add_argument("--pool", action="store_true",
                    help="for cases already in the output: run --paths more with this --seed's stream and pool them "
                         "with the stored values (pool_runs), instead of skipping the case")
    args = ap.parse_args()
    doc = json.loads(args.out.read_text()) if args.out.exists() else {
        "description": DESCRIPTION,
        "generator": "benchmarks/low_sun_montecarlo_reference.py",
        "wavelengths_nm": WAVELENGTHS, "views_deg": views(), "sun_azimuth_deg": 0.0, "observer_altitude_m": 0.0,
        "atmospheres": {k: v[0] for k, v in ATMOSPHERES.items()}, "cases": []}
    done = {(c["atmosphere"], c["sun_elevation_deg"]): i for i, c in enumerate(doc["cases"])}
    for name in args.atmospheres.split(","):
        for s in (float(x) for x in args.suns.split(",")):
            if (name, s) in done and not args.pool:
                continue
            seed = args.seed + 1 + CASE_ORDER.index((name, s))
            if (name, s) in done:
                check_new_seed(doc["cases"][done[(name, s)]], seed)  # before the run, not after it
            case = run_case(name, s, args.paths, seed)
            if (name, s) in done:
                i = done[(name, s)]
                doc["cases"][i] = case = pool_runs(doc["cases"][i], case)
            else:
                doc["cases"].append(case)
            with atomic_path(args.out) as tmp:
                Path(tmp).write_text(json.dumps(doc, indent=1))
            rel = np.array(case["radiance_stderr"]) / np.array(case["radiance"])
            print(f"{name} sun {s:+g}: {case['paths']} paths, {case['seconds']} s, relative stderr median "
                  f"{100 * np.median(rel):.1f} % max {100 * rel.max():.1f} %", flush=True)


if __name__ == "__main__":
    main()
