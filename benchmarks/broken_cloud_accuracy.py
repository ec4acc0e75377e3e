"""The ``broken-cloud`` sky model against the Monte Carlo: domain-mean ground irradiance and the view from above.

Reads what ``benchmarks/broken_cloud_domain_montecarlo.py`` wrote (tests/data/broken_cloud_domain_montecarlo.json,
tests/data/broken_cloud_above_montecarlo.npz: scene, seeds and photon / path counts are stored there) and evaluates
:class:`skyscatter.sky.broken_cloud.BrokenCloudSky` on the same fields, air and sun (``interpolation="voxel"``: the
field as the Monte Carlo traces it; ``--interpolation linear`` for the model's default):

* ``irradiance``: :meth:`~skyscatter.sky.broken_cloud.BrokenCloudSky.domain_ground_irradiance` (direct over
  every column centre, diffuse over ``--points`` x ``--points`` ground points with ``--zeniths`` x
  ``--azimuths`` directions each) / (mu0 F0) against the forward photons' domain means at 450 / 550 / 650 nm:
  global, direct and diffuse ratios model / MC;
* ``above``: the model's radiance along the pixels of the Monte Carlo's nadir fisheye from 10 km; per-pixel
  relative difference model / MC - 1 (RMS, 95th percentile of its magnitude, median), the ratio of the disc
  means, and region means (3 bands of the nadir angle x the half towards and away from the sun); a picture
  docs/images/broken_cloud_above_vs_montecarlo.png (top row the Monte Carlo, bottom row the model, covers 0.3 /
  0.6 / 0.9 left to right, 650 / 550 / 450 nm as red / green / blue, one exposure).

Writes benchmarks/broken_cloud_accuracy.json and prints the figures. Usage:
``python benchmarks/broken_cloud_accuracy.py [irradiance] [above] [--points 8] [--octaves a b c d e]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from broken_cloud_domain_montecarlo import ABOVE, ABOVE_ALTITUDE, IRRADIANCE  # noqa: E402
from broken_cloud_montecarlo import field_for  # noqa: E402
from fit_broken_cloud import figures  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.fileio import atomic_path  # noqa: E402
from skyscatter.sky.broken_cloud import BrokenCloudSky  # noqa: E402

RESULT = Path(__file__).with_suffix(".json")
IMAGES = Path(__file__).parents[1] / "docs" / "images"


def model_irradiance(case: dict, scene: dict, *, points: int, zeniths: int, azimuths: int,
                     interpolation: str, octaves: tuple | None = None) -> dict:
    """The model's domain means / (mu0 F0) for one stored Monte Carlo case, and the ratios."""
    air = AtmosphereParameters(ground_albedo=scene["ground_albedo"])
    zen = math.radians(90.0 - case["sun_elevation_deg"])
    wl = np.asarray(scene["wavelengths_nm"], dtype=float)
    sky = BrokenCloudSky(zen, math.radians(scene["sun_azimuth_deg"]), clouds=field_for(case["cover"], scene),
                         atmosphere=air, interpolation=interpolation)
    if octaves:
        sky.octaves = tuple(octaves)
    t0 = time.perf_counter()
    direct, diffuse = sky.domain_ground_irradiance(wl, points_per_axis=points, zeniths=zeniths, azimuths=azimuths)
    secs = time.perf_counter() - t0
    norm = math.cos(zen) * np.asarray(air.solar_irradiance_at(wl), dtype=float)
    direct, diffuse = direct / norm, diffuse / norm
    mc_g, mc_dir, mc_dif = (np.asarray(case[k]) for k in ("global", "direct", "diffuse"))
    return {"model_global": (direct + diffuse).round(5).tolist(), "model_direct": direct.round(5).tolist(),
            "model_diffuse": diffuse.round(5).tolist(),
            "ratio_global": ((direct + diffuse) / mc_g).round(4).tolist(),
            "ratio_direct": (direct / mc_dir).round(4).tolist(), "ratio_diffuse": (diffuse / mc_dif).round(4).tolist(),
            "mc_relative_stderr": (np.asarray(case["global_stderr"]) / mc_g).round(4).tolist(),
            "seconds": round(secs, 1)}


def irradiance(args, out: dict) -> None:
    mc = json.loads(IRRADIANCE.read_text())
    scene = mc["scene"]
    res = out.setdefault(f"irradiance_{args.interpolation}{_tag(args)}", {})
    res["settings"] = {"points_per_axis": args.points, "zeniths": args.zeniths, "azimuths": args.azimuths}
    for key, case in mc["cases"].items():
        r = model_irradiance(case, scene, points=args.points, zeniths=args.zeniths, azimuths=args.azimuths,
                             interpolation=args.interpolation, octaves=args.octaves)
        res[key] = r
        print(f"{key}: global {r['ratio_global']} direct {r['ratio_direct']} diffuse {r['ratio_diffuse']} "
              f"(MC stderr {r['mc_relative_stderr']}; {r['seconds']} s, load {os.getloadavg()[0]:.1f})", flush=True)


def regions(dirs: np.ndarray, sun: np.ndarray) -> np.ndarray:
    """Region of each pixel: 3 bands of the nadir angle (0-30, 30-60, 60-90 deg) x the half of the view towards
    the sun's azimuth and the half away from it."""
    nadir = np.degrees(np.arccos(np.clip(-dirs[:, 2], -1.0, 1.0)))
    towards = (dirs[:, :2] @ sun[:2]) > 0.0
    return np.digitize(nadir, [30.0, 60.0]) * 2 + towards.astype(int)


def above(args, out: dict) -> None:
    from skyscatter.render import write_png

    data = np.load(ABOVE)
    meta = json.loads(str(data["meta"]))
    dirs, wl, inside = data["directions"], data["wavelengths"], data["inside"]
    air = AtmosphereParameters(ground_albedo=meta["ground_albedo"])
    res = out.setdefault(f"above_{args.interpolation}{_tag(args)}", {})
    pics = [[], []]
    for i, cover in enumerate(float(c) for c in data["covers"]):
        if f"radiance_{i}" not in data:
            continue
        mc, se = data[f"radiance_{i}"], data[f"stderr_{i}"]
        sky = BrokenCloudSky(math.radians(meta["sun_zenith_deg"]), math.radians(meta["sun_azimuth_deg"]),
                             clouds=field_for(cover, meta), atmosphere=air, altitude=ABOVE_ALTITUDE,
                             interpolation=args.interpolation)
        if args.octaves:
            sky.octaves = tuple(args.octaves)
        t0 = time.perf_counter()
        model = sky.spectral_radiance(dirs, wl)
        fig = figures(model, mc, se)
        fig["seconds"] = round(time.perf_counter() - t0, 1)
        reg = regions(dirs, sky.sun_direction)
        fig["regions"] = {}
        for r in np.unique(reg):
            sel = reg == r
            band, towards = divmod(int(r), 2)
            name = f"nadir {30 * band}-{30 * band + 30} deg, {'towards' if towards else 'away from'} the sun"
            fig["regions"][name] = {"pixels": int(sel.sum()),
                                    "ratio": (model[sel].mean(axis=0) / mc[sel].mean(axis=0)).round(3).tolist(),
                                    "mc_relative_stderr": (np.sqrt((se[sel] ** 2).sum(axis=0)) / mc[sel].sum(axis=0)
                                                           ).round(4).tolist()}
        res[str(cover)] = fig
        print(f"above, cover {cover}: {json.dumps(fig)}", flush=True)
        for row, values in enumerate((mc, model)):
            pic = np.zeros((*inside.shape, 3))
            pic[inside] = values[:, ::-1]  # 650, 550, 450 nm as R, G, B
            pics[row].append(np.kron(pic, np.ones((8, 8, 1))))
    if pics[0] and not args.octaves:
        gap_v = np.zeros((pics[0][0].shape[0], 8, 3))
        rows = [np.concatenate(sum(([p, gap_v] for p in row), [])[:-1], axis=1) for row in pics]
        both = np.concatenate([rows[0], np.zeros((8, rows[0].shape[1], 3)), rows[1]], axis=0)
        name = "broken_cloud_above_vs_montecarlo.png" if args.interpolation == "voxel" else \
            f"broken_cloud_above_vs_montecarlo_{args.interpolation}.png"
        print(write_png(IMAGES / name, both / both[both > 0].mean() * 0.18, key=0.45))


def _tag(args) -> str:
    """Key suffix of results with other octaves than the shipped ones."""
    return "_octaves_" + "_".join(f"{v:g}" for v in args.octaves) if args.octaves else ""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", nargs="*", default=["irradiance", "above"], help="irradiance and/or above (both)")
    ap.add_argument("--points", type=int, default=8, help="ground points per axis of the diffuse part")
    ap.add_argument("--zeniths", type=int, default=32, help="zenith nodes of the diffuse part")
    ap.add_argument("--azimuths", type=int, default=64, help="azimuth nodes of the diffuse part")
    ap.add_argument("--interpolation", default="voxel", choices=["voxel", "linear"])
    ap.add_argument("--octaves", type=float, nargs=5, help="(a, b, c, d, e) instead of FITTED_OCTAVES (refits)")
    args = ap.parse_args()
    if set(args.what) - {"irradiance", "above"}:
        ap.error("what must be irradiance and/or above")
    print(f"machine: {len(os.sched_getaffinity(0))} cores, load average {os.getloadavg()[0]:.1f}", flush=True)
    out = json.loads(RESULT.read_text()) if RESULT.exists() else {}
    for what in args.what:
        (irradiance if what == "irradiance" else above)(args, out)
        with atomic_path(RESULT) as tmp:
            Path(tmp).write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {RESULT}")


if __name__ == "__main__":
    main()
