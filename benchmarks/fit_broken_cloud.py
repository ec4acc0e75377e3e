"""Fit the ``broken-cloud`` sky's multiple-scattering octaves ``(a, b, c, d, e)`` to Monte Carlo radiances.

Reads tests/data/broken_cloud_montecarlo.npz (``benchmarks/broken_cloud_montecarlo.py``: the scene, the Monte
Carlo seeds and path counts are stored in it), evaluates :class:`skyscatter.sky.broken_cloud.BrokenCloudSky` on
the same field (``interpolation="voxel"``: the field as the Monte Carlo traces it), sun and fisheye pixels at
450 / 550 / 650 nm, and minimises by least squares (scipy's
``least_squares``, trust-region reflective, bounds a in [0.01, 1], b in [0, 0.99], c in [0, 1], d in [0, 2],
e in [0, 2]: the exponent of the octaves' entering-energy factors, ``skyscatter.sky.broken_cloud.entry_factors``)

    sum over pixels and wavelengths of ((model - MC) / (stderr_MC + 0.05 MC))^2

over 15 regions of the fisheye (5 bands of the angle from the sun x 3 bands of elevation, 30-150 pixels each;
means of model and Monte Carlo, ``stderr`` the region mean's): the Monte Carlo's per-pixel values are
heavy-tailed (median relative standard error 9-15 % per pixel, most pixels below their expectation and a few far
above: next-event estimates through the droplets' diffraction peak), so that per-pixel (or 4 x 4 block) weights
favour the pixels that came out low and pull the fit below the expectation (measured: 4 x 4 blocks gave region
means 30-36 % below the Monte Carlo's). Fitted on the covers ``--fit-cover`` (default 0.6); the other
covers are held out and only compared. ``--irradiance`` adds the domain-mean diffuse ground irradiance of the
six cases of tests/data/broken_cloud_domain_montecarlo.json (covers 0.3 / 0.6 / 0.9, sun 30 and 60 deg high;
``benchmarks/broken_cloud_domain_montecarlo.py``) as residuals ``(model - MC) / (0.02 MC)`` per wavelength
(:meth:`~skyscatter.sky.broken_cloud.BrokenCloudSky.domain_ground_irradiance` on 4 x 4 ground points x 16 x 32
directions: the fit's quadrature; the comparison, ``benchmarks/broken_cloud_accuracy.py``, uses 8 x 8 x 32 x 64);
``--above`` adds the 6 region means (3 bands of nadir angle x towards / away from the sun) of the nadir fisheye
from 10 km (tests/data/broken_cloud_above_montecarlo.npz) of each fitted cover, weighted like the fisheye's.
Prints and writes ``--out`` (default benchmarks/fit_broken_cloud.json, the shipped fit): the fitted numbers, the
residuals per cover (RMS and 95th percentile of the relative difference per pixel, mean ratio per wavelength)
before and after the fit. The numbers are then copied by hand into
``skyscatter.sky.broken_cloud.FITTED_OCTAVES``. The refits across covers, suns and views
(benchmarks/fit_broken_cloud_irradiance.json: ``--fit-cover 0.3 0.6 0.9 --irradiance``;
benchmarks/fit_broken_cloud_all.json: the same with ``--above``) were not adopted (docs/clouds.md). With the
entering-energy exponent ``e`` (benchmarks/fit_broken_cloud_entry.json and fit_broken_cloud_entry_above.json,
``--max-nfev 30``/``40``) the shipped octaves lie between those fits and the first (the JSON's "chosen" field).
With the ground-cloud coupling and the light shafts on (2026-12-02), benchmarks/fit_broken_cloud_shafts.json
(``--fit-cover 0.3 0.6 0.9 --irradiance --above --max-nfev 12``) was not adopted either (docs/clouds.md, "Why
dense fields were short").
With the droplets' forward peak truncated delta-M style in the march (2026-12-02,
``skyscatter.sky.broken_cloud.delta_m_octaves``, ``--truncation-streams 16``):
benchmarks/fit_broken_cloud_delta_m.json (``--fit-cover 0.3 0.6 0.9 --free a b c --x0 0.3245 0.55 0.6334 0 0.5
--max-nfev 10``: ``d`` and ``e`` held) and fit_broken_cloud_delta_m_irradiance.json (``--irradiance --free b --x0
0.4559 0.70 0.6411 0 0.5 --max-nfev 5``, the same covers); neither adopted, the truncation is off (docs/clouds.md,
"The forward peak kept near the sun"). The joint fit of ``a, b, c, e`` against every guard of the tests at once
(minimax over the guards' margins): ``benchmarks/fit_broken_cloud_joint.py``.
``--free`` names the parameters fitted (the others held at ``--x0``).
With the octaves' phases the droplets' phase convolved (2026-12-03, ``--octave-phase convolved``, the default:
``skyscatter.sky.broken_cloud.OCTAVE_PHASE``): benchmarks/fit_broken_cloud_convolved.json (``--fit-cover 0.3 0.6
0.9 --free a b c --x0 0.3245 0.693 0.6334 0 0.5 --max-nfev 10``) and, from its result,
benchmarks/fit_broken_cloud_convolved_irradiance.json (``--fit-cover 0.3 0.6 0.9 --irradiance --free a b c --x0
0.4414 0.7139 0.6803 0 0.5 --max-nfev 6``), neither adopted (docs/clouds.md, "The octaves' phases");
``--octave-phase henyey-greenstein`` for the lobes of the fits above.

Usage: ``python benchmarks/fit_broken_cloud.py [--fit-cover 0.6 ...] [--irradiance] [--above] [--free a b c]
[--out FILE]``.
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
from scipy.optimize import least_squares

sys.path.insert(0, str(Path(__file__).parent))
from broken_cloud_domain_montecarlo import IRRADIANCE  # noqa: E402
from broken_cloud_montecarlo import OUT as DATA  # noqa: E402
from broken_cloud_montecarlo import field_for  # noqa: E402
from skyscatter.atmosphere import AtmosphereParameters  # noqa: E402
from skyscatter.sky import broken_cloud  # noqa: E402
from skyscatter.sky.broken_cloud import FITTED_OCTAVES, BrokenCloudSky  # noqa: E402

RESULT = Path(__file__).with_suffix(".json")
#: The octaves' parameters (skyscatter.sky.broken_cloud.FITTED_OCTAVES).
NAMES = ("a", "b", "c", "d", "e")
LOWER = np.array([0.01, 0.0, 0.0, 0.0, 0.0])
UPPER = np.array([1.0, 0.99, 1.0, 2.0, 2.0])


def figures(model: np.ndarray, mc: np.ndarray, se: np.ndarray) -> dict:
    """Per-pixel relative differences model / MC - 1 at each wavelength: RMS, 95th percentile of |.|, median, the
    Monte Carlo's median relative standard error; and the ratio of the means."""
    rel = model / mc - 1.0
    return {"mc_median_relative_stderr": np.median(se / mc, axis=0).round(4).tolist(),
            "rms": np.sqrt(np.mean(rel**2, axis=0)).round(4).tolist(),
            "p95": np.percentile(np.abs(rel), 95, axis=0).round(4).tolist(),
            "median": np.median(rel, axis=0).round(4).tolist(),
            "mean_ratio": (model.mean(axis=0) / mc.mean(axis=0)).round(4).tolist()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit-cover", type=float, nargs="+", default=[0.6])
    ap.add_argument("--irradiance", action="store_true", help="fit the domain-mean diffuse ground irradiance too")
    ap.add_argument("--out", type=Path, default=RESULT, help="the JSON written (default: the shipped fit's)")
    ap.add_argument("--above", action="store_true",
                    help="fit the region means of the nadir fisheye from 10 km too (the --fit-cover covers)")
    ap.add_argument("--max-nfev", type=int, default=None, help="at most this many evaluations")
    ap.add_argument("--x0", type=float, nargs=5, default=[0.3, 0.7, 0.7, 0.3, 0.5], help="start (a, b, c, d, e)")
    ap.add_argument("--free", nargs="+", choices=list(NAMES), default=list(NAMES),
                    help="the parameters fitted (the others held at --x0)")
    ap.add_argument("--truncation-streams", type=int, default=broken_cloud.TRUNCATION_STREAMS,
                    help="the march's delta-M truncation (skyscatter.sky.broken_cloud.TRUNCATION_STREAMS; 0: off)")
    ap.add_argument("--octave-phase", choices=("convolved", "henyey-greenstein"), default=broken_cloud.OCTAVE_PHASE,
                    help="the octaves' phase functions (skyscatter.sky.broken_cloud.OCTAVE_PHASE)")
    args = ap.parse_args()
    broken_cloud.TRUNCATION_STREAMS = args.truncation_streams
    broken_cloud.OCTAVE_PHASE = args.octave_phase
    free = [NAMES.index(n) for n in args.free]
    start = np.array(args.x0, dtype=float)

    def full(x):
        theta = start.copy()
        theta[free] = x
        return theta

    data = np.load(DATA)
    meta = json.loads(str(data["meta"]))
    covers = [float(c) for c in data["covers"]]
    wl = data["wavelengths"]
    dirs = data["directions"]
    air = AtmosphereParameters(ground_albedo=meta["ground_albedo"])
    skies = [BrokenCloudSky(math.radians(meta["sun_zenith_deg"]), math.radians(meta["sun_azimuth_deg"]),
                            clouds=field_for(c, meta), atmosphere=air, interpolation="voxel") for c in covers]
    print(f"load average {os.getloadavg()[0]:.1f}; Monte Carlo: {meta['samples']} paths per pixel, seeds "
          f"{meta['seeds']}, {dirs.shape[0]} pixels, covers {covers}")
    fit_idx = [covers.index(c) for c in args.fit_cover]
    sky = skies[fit_idx[0]]

    def evaluate(s: BrokenCloudSky, theta) -> np.ndarray:
        s.octaves = tuple(float(v) for v in theta)
        return s.spectral_radiance(dirs, wl)

    # regions: 5 bands of the angle from the sun x 3 bands of elevation (30-150 pixels each)
    cos_sun = dirs @ sky.sun_direction
    region = np.digitize(cos_sun, [0.0, 0.5, 0.8, 0.95]) * 3 + np.digitize(dirs[:, 2], [0.3, 0.6])
    _, block = np.unique(region, return_inverse=True)
    nb = block.max() + 1
    count = np.bincount(block, minlength=nb)[:, None]

    def block_mean(v: np.ndarray) -> np.ndarray:
        return np.stack([np.bincount(block, v[:, j], minlength=nb) for j in range(v.shape[1])], axis=1) / count

    mc_b = {i: block_mean(data[f"radiance_{i}"]) for i in fit_idx}
    se_b = {i: np.sqrt(block_mean(data[f"stderr_{i}"] ** 2) / count) for i in fit_idx}
    irr_cases = []
    if args.irradiance:
        dom = json.loads(IRRADIANCE.read_text())
        for case in dom["cases"].values():
            zen = math.radians(90.0 - case["sun_elevation_deg"])
            s_ = BrokenCloudSky(zen, math.radians(dom["scene"]["sun_azimuth_deg"]),
                                clouds=field_for(case["cover"], dom["scene"]), atmosphere=air, interpolation="voxel")
            norm = math.cos(zen) * np.asarray(air.solar_irradiance_at(wl), dtype=float)
            irr_cases.append((s_, norm, np.asarray(case["diffuse"])))

    def irr_residuals(theta) -> np.ndarray:
        out = []
        for s_, norm, mc_dif in irr_cases:
            s_.octaves = tuple(float(v) for v in theta)
            _, dif = s_.domain_ground_irradiance(wl, points_per_axis=4, direct_points=1, zeniths=16, azimuths=32)
            out.append((dif / norm - mc_dif) / (0.02 * mc_dif))
        return np.concatenate(out) if out else np.zeros(0)

    above_cases = []
    if args.above:
        from broken_cloud_accuracy import regions
        from broken_cloud_domain_montecarlo import ABOVE, ABOVE_ALTITUDE

        up = np.load(ABOVE)
        ameta = json.loads(str(up["meta"]))
        adirs = up["directions"]
        for i in fit_idx:
            s_ = BrokenCloudSky(math.radians(ameta["sun_zenith_deg"]), math.radians(ameta["sun_azimuth_deg"]),
                                clouds=field_for(covers[i], ameta), atmosphere=air, altitude=ABOVE_ALTITUDE,
                                interpolation="voxel")
            reg = regions(adirs, s_.sun_direction)
            n_r = reg.max() + 1
            cnt = np.bincount(reg, minlength=n_r)[:, None]

            def rmean(v, reg=reg, n_r=n_r, cnt=cnt):
                return np.stack([np.bincount(reg, v[:, j], minlength=n_r) for j in range(v.shape[1])], axis=1) / cnt

            above_cases.append((s_, rmean, rmean(up[f"radiance_{i}"]),
                                np.sqrt(rmean(up[f"stderr_{i}"] ** 2) / cnt)))

    def above_residuals(theta) -> list[np.ndarray]:
        out = []
        for s_, rmean, mc_r, se_r in above_cases:
            s_.octaves = tuple(float(v) for v in theta)
            out.append(((rmean(s_.spectral_radiance(adirs, wl)) - mc_r) / (se_r + 0.03 * mc_r)).ravel())
        return out

    def residuals(theta) -> np.ndarray:
        parts = [((block_mean(evaluate(skies[i], theta)) - mc_b[i]) / (se_b[i] + 0.03 * mc_b[i])).ravel()
                 for i in fit_idx]
        return np.concatenate(parts + above_residuals(theta) + [irr_residuals(theta)])

    before = {str(c): figures(evaluate(s, FITTED_OCTAVES), data[f"radiance_{i}"], data[f"stderr_{i}"])
              for i, (c, s) in enumerate(zip(covers, skies, strict=True))}
    t0 = time.perf_counter()
    cpu0 = time.process_time()
    fit = least_squares(lambda x: residuals(full(x)), x0=start[free], bounds=(LOWER[free], UPPER[free]),
                        x_scale=0.1, verbose=2, max_nfev=args.max_nfev)
    secs = time.perf_counter() - t0
    cpu = time.process_time() - cpu0
    theta = tuple(round(float(v), 4) for v in full(fit.x))
    after = {str(c): figures(evaluate(s, theta), data[f"radiance_{i}"], data[f"stderr_{i}"])
             for i, (c, s) in enumerate(zip(covers, skies, strict=True))}
    irr = {}
    if irr_cases:  # ratio model / MC of the domain-mean diffuse ground irradiance per case, at the fit's quadrature
        keys = list(json.loads(IRRADIANCE.read_text())["cases"])
        for name, theta_ in (("before", FITTED_OCTAVES), ("after", theta)):
            z = irr_residuals(theta_).reshape(len(keys), -1)
            irr[name] = {k: (1.0 + 0.02 * z[j]).round(4).tolist() for j, k in enumerate(keys)}
    out = {"octaves_a_b_c_d": theta, "fit_cover": args.fit_cover, "irradiance": args.irradiance, "above": args.above,
           "irradiance_diffuse_ratio": irr, "cost": float(fit.cost), "nfev": int(fit.nfev),
           "seconds": round(secs, 1), "cpu_seconds": round(cpu, 1), "load_average": os.getloadavg()[0],
           "free": args.free, "truncation_streams": broken_cloud.TRUNCATION_STREAMS,
           "octave_phase": broken_cloud.OCTAVE_PHASE,
           "monte_carlo": {k: meta[k] for k in meta},
           "wavelengths_nm": wl.tolist(), "before_fit_with": list(FITTED_OCTAVES), "before": before, "after": after}
    args.out.write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps({"octaves": theta, "after": after, "before": before}, indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
