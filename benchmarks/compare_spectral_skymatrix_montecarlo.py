"""Spectral sky matrix and gensdaymtx against the Monte Carlo reference, side by side (issue 24, item 3).

A year of weather made by tests/weather_synth.py ``write_year_epw`` (seed 24: SPECTRL2 clear days, broken and
overcast days). **Hours**: ``--hours`` (20) drawn with ``--seed`` (7) among the daylit hours our retrieval
calls clear, broken (the clear / overcast blend) and cloudy (overcast, sky cover >= 8 tenths): a quarter each
of clear, broken and overcast hours with the sun at zenith < 70 deg, and a quarter "low sun" (zenith 70-86 deg,
drawn evenly from the three kinds). The hours are run interleaved (clear, broken, overcast, low, clear, ...), so
a partial run holds every kind.

**Patches**: per hour the Tregenza patches nearest 19 directions in the sun's frame (altitudes 6-66 deg every
12 deg at 0, 90 and 180 deg from the sun's azimuth, and the zenith; ``tests/skymatrix_mc.py``), minus those
within 5 deg of the sun (10 deg for the overcast parts). **Wavelengths** 410, 490, 570, 650 nm (centres of
gensdaymtx's 20 nm bands, nodes of our tables).

**The Monte Carlo** runs through the same air and clouds as ours (``tests/skymatrix_mc.py`` says which; broken
hours are ``(1 - f) MC_clear + f MC_overcast``, the matrix's own blend). Paths: a pilot of ``--pilot`` (512)
paths per direction per sky, then more paths so that the 90th percentile over the hour's patches and
wavelengths of the relative standard error reaches ``--target`` (2.5 %), within the time left (``--budget``
minutes of CPU, shared evenly over the skies still to run), in calls of at most ``--chunk`` paths, each with its
own seed (``1000 hour + 10 part`` for the pilot, then one more per call), all pooled; the JSON lists every sky's
runs (seed, paths, CPU seconds). Dask's synchronous scheduler: one core.

**Resuming** (``--resume`` earlier JSON, repeatable): a sky whose earlier Monte Carlo ran through the same air
(the retrieved aerosol optical depth and albedo, or cloud optical depth; the same sun and patches) starts from
those paths instead of a pilot (files written before 2026-12-04 hold no seeds: their runs are the pilot at the
first seed and the follow-up at the next, what this script did); gensdaymtx's columns are taken from it, and
gensdaymtx is not run. ``--kinds`` (default all) says which kinds of hours (low-sun hours by their kind) get new
paths; the other hours are carried from the earlier file with their Monte Carlo as it was and our matrix
recomputed; ``--only`` restricts the new paths to some hours (to split a run over processes, gathered afterwards
by ``--budget 0`` with every file resumed). ``--subset`` (overcast hours only) retrieves and computes our matrix on
a record of those hours alone (:func:`prepare_subset`), every other hour carried verbatim from the first resumed
file. ``--retrieval`` pickles the year's retrieval (read when it exists). Our matrix is computed for the picked
hours only.

**Ours** is the matrix itself (``spectral_sky_matrix``, Tregenza, one cell per patch, 5 nm bands centred at those
wavelengths with their neighbours, no gases, over the band's E0 and the day's eccentricity); **gensdaymtx's** the
patch value of its ``-m 1`` matrix in the 20 nm bands centred there, divided by 400 nm (:data:`GENSDAYMTX_SPAN_NM`:
each of its band values is a spectral radiance in W m^-2 sr^-1 nm^-1 times the 380-780 nm span), over the band's
E0 and eccentricity. It is compared twice: on that scale and divided by its per-hour median ratio (the shape of
its sky).

Results go to ``--out`` (JSON, rewritten atomically after every hour, so a stopped run keeps what finished);
``--plot`` redraws the figure docs/images/spectral_skymatrix_montecarlo.png and prints the table from a JSON.

Usage: ``python benchmarks/compare_spectral_skymatrix_montecarlo.py [--hours 20] [--budget 50] [--out X.json]
[--kinds overcast --resume OLD.json]``,
``python benchmarks/compare_spectral_skymatrix_montecarlo.py --plot X.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
WAVELENGTHS = (410.0, 490.0, 570.0, 650.0)
#: gensdaymtx's band values are spectral radiances [W m^-2 sr^-1 nm^-1] times this span [nm] (Radiance,
#: src/gen/gensdaymtx.c: ``sky_radiance[k] *= WVLSPAN`` for the clear sky of its tables, whose sun is EXTSOL in
#: W m^-2 nm^-1; src/gen/atmos.c: ``WVLSPAN = 400  // 380nm to 780nm``; the overcast part, the CIE overcast
#: luminance over D65's efficacy times a relative spectrum of mean about 1, is on the same scale): the mean over
#: its 20 bands is the 380-780 nm radiance, Radiance's convention for spectral channels.
GENSDAYMTX_SPAN_NM = 400.0
KINDS = ("clear", "broken", "overcast")


def gensdaymtx_matrix(epw: Path, cache: Path | None = None) -> np.ndarray:
    """gensdaymtx -m 1 -s (the sky without the sun, which gensdaymtx otherwise puts into the patches around it):
    (hours, 145 patches, 20 bands, short to long); run in ``cache`` (its atmos_data)."""
    import pyradiance

    root = Path(pyradiance.__file__).parent
    if cache is None:
        cache = Path(os.environ.get("SKYSCATTER_CACHE_DIR", tempfile.gettempdir())) / "radiance"
    cache.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, RAYPATH=f".{os.pathsep}{root / 'lib'}")
    out = subprocess.run([str(root / "bin" / "gensdaymtx"), "-m", "1", "-s", str(epw)], cwd=cache, env=env,
                         capture_output=True, check=True).stdout
    head, body = out.split(b"\n\n", 1)
    text = head.decode()
    nrows = int(text.split("NROWS=")[1].split()[0])
    ncols = int(text.split("NCOLS=")[1].split()[0])
    ncomp = int(text.split("NCOMP=")[1].split()[0])
    vals = np.array(body.split(), dtype=float).reshape(nrows, ncols, ncomp)
    return vals[1:, :, ::-1].transpose(1, 0, 2)  # drop the ground row; components short to long


def pick_hours(h, n: int, seed: int) -> list[tuple[int, str]]:
    """The hours (index, kind), interleaved by stratum (module docstring)."""
    from skyscatter.fit.weather import BROKEN, CLEAR, CLOUDY

    rng = np.random.default_rng(seed)
    zen = np.degrees(h.sun_zenith)
    code = {"clear": CLEAR, "broken": BROKEN, "overcast": CLOUDY}
    ok = {k: (h.status == c) & ((c != CLOUDY) | ~(h.cloud_cover < 0.8)) for k, c in code.items()}
    strata = []
    per = [n // 4 + (1 if s < n % 4 else 0) for s in range(4)]
    for s, kind in enumerate(KINDS):
        pool = np.flatnonzero(ok[kind] & (zen < 70.0))
        strata.append([(int(i), kind, False) for i in rng.choice(pool, size=min(per[s], pool.size), replace=False)])
    low = []
    for j in range(per[3]):
        kind = KINDS[j % 3]
        pool = np.setdiff1d(np.flatnonzero(ok[kind] & (zen >= 70.0) & (zen < 86.0)), [x[0] for x in low])
        if pool.size:
            low.append((int(rng.choice(pool)), kind, True))
    strata.append(low)
    out = []
    for k in range(max(len(s) for s in strata)):
        out += [s[k] for s in strata if k < len(s)]
    return out


def gens_per_nm(res: dict) -> bool:
    """Put gensdaymtx's columns of a results JSON written before 2026-12-02 (its band values as they are) on the
    per-nm scale (over :data:`GENSDAYMTX_SPAN_NM`); True if anything changed. The shape columns do not change."""
    if res.get("gens_scale") == "per nm":
        return False
    for row in res["hours"]:
        if row.get("gens_value") is None:
            continue
        r_g = np.asarray(row["gens_value"]) / GENSDAYMTX_SPAN_NM
        ratio = r_g / np.asarray(row["mc_rel"])
        row.update({"gens_value": r_g.tolist(), "gens_rel": (ratio - 1).tolist(),
                    "gens_median_ratio": float(np.median(ratio))})
    res["gens_scale"] = "per nm"
    return True


def summarise(res: dict) -> list[str]:
    """Table rows: per hour type and wavelength, median / p95 |error| of ours and gensdaymtx's vs the MC."""
    rows = res["hours"]
    wl = res["wavelengths"]
    lines = ["| hours | n | wavelength [nm] | MC SE median | ours median | ours median abs | ours p95 abs | "
             "gensdaymtx / MC (median) | gensdaymtx median abs | p95 abs | gensdaymtx shape: median abs | p95 abs |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    groups = [("clear", lambda r: r["kind"] == "clear" and not r["low_sun"]),
              ("broken", lambda r: r["kind"] == "broken" and not r["low_sun"]),
              ("overcast", lambda r: r["kind"] == "overcast" and not r["low_sun"]),
              ("low sun (70-86 deg)", lambda r: r["low_sun"]), ("all", lambda r: True)]
    for name, sel in groups:
        hs = [r for r in rows if sel(r)]
        if not hs:
            continue
        for k, w in enumerate([*wl, "all"]):
            def col(key, hs=hs, k=k, w=w):
                a = [np.asarray(r[key], dtype=float) for r in hs if r.get(key) is not None]
                if not a:
                    return np.array([np.nan])
                a = np.concatenate([x[:, k] if w != "all" else x.ravel() for x in a])
                return a[np.isfinite(a)]
            o, se, g, gs = col("ours_rel"), col("mc_rel_se"), col("gens_rel"), col("gens_shape_rel")
            f = lambda a, q: float(np.percentile(np.abs(a), q)) * 100 if a.size else float("nan")  # noqa: E731
            m = lambda a: float(np.median(a)) * 100 if a.size else float("nan")  # noqa: E731
            ratio = float(np.median(g + 1.0)) if g.size else float("nan")
            lines.append(f"| {name} | {len(hs)} | {w if w == 'all' else int(w)} | {m(se):.1f} % | {m(o):+.1f} % | "
                         f"{f(o, 50):.1f} % | {f(o, 95):.1f} % | {ratio:.2f} | {f(g, 50):.1f} % | {f(g, 95):.1f} % | "
                         f"{f(gs, 50):.1f} % | {f(gs, 95):.1f} % |")
    cloudy = [r for r in rows if "cloudysky_vs_mc" in r]
    if cloudy:
        lines += ["", "| hours with an overcast part | n | CloudySky vs MC overcast: median | median abs | p95 abs | "
                      "ours vs (1 - f) MC clear + f CloudySky: median | median abs | p95 abs |",
                  "|---|---|---|---|---|---|---|---|"]
        for name, sel in groups[1:]:
            hs = [r for r in cloudy if sel(r)]
            if not hs:
                continue
            a = np.concatenate([np.asarray(r["cloudysky_vs_mc"]).ravel() for r in hs])
            b = np.concatenate([np.asarray(r["ours_vs_cloudysky_blend"]).ravel() for r in hs])
            lines.append(f"| {name} | {len(hs)} | {np.median(a) * 100:+.1f} % | {np.median(abs(a)) * 100:.1f} % | "
                         f"{np.percentile(abs(a), 95) * 100:.1f} % | {np.median(b) * 100:+.1f} % | "
                         f"{np.median(abs(b)) * 100:.1f} % | {np.percentile(abs(b), 95) * 100:.1f} % |")
    return lines


def plot(res: dict, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = res["hours"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.6), gridspec_kw={"width_ratios": [3, 1.2]})
    ax = axes[0]
    pos = np.arange(len(rows))
    ours = [np.asarray(r["ours_rel"]).ravel() * 100 for r in rows]
    shape = [np.asarray(r["gens_rel"]).ravel() * 100 if r.get("gens_rel") is not None else [np.nan]
             for r in rows]
    se = [2 * np.median(np.asarray(r["mc_rel_se"])) * 100 for r in rows]
    ax.boxplot(ours, positions=pos - 0.18, widths=0.3, whis=(5, 95), showfliers=False, patch_artist=True,
               boxprops={"facecolor": "tab:blue", "alpha": 0.6})
    ax.boxplot(shape, positions=pos + 0.18, widths=0.3, whis=(5, 95), showfliers=False, patch_artist=True,
               boxprops={"facecolor": "tab:orange", "alpha": 0.6})
    ax.fill_between(pos, [-s for s in se], se, color="0.8", zorder=0, step="mid", label="MC 2 SE (median)")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xticks(pos, [f"{r['hour']} {r['kind'][0]}{'L' if r['low_sun'] else ''} {r['sun_zenith_deg']:.0f}"
                        for r in rows], rotation=70, fontsize=7)
    ax.set_ylim(-80, 80)
    ax.set_xlabel("hour of year, kind (c/b/o, L low sun), sun zenith [deg]; whiskers 5-95 % of patches x 4 wavelengths")
    ax.set_ylabel("relative to Monte Carlo [%]")
    ax.set_title("skyscatter (blue) and gensdaymtx (orange: band values / 400 nm; no illuminance in the file, so "
                 "not calibrated to its DHI) vs Monte Carlo", fontsize=9)
    ax.legend(loc="lower left", fontsize=7)
    ax = axes[1]
    for r in rows:
        o = np.asarray(r["mc_rel"]).ravel()
        ax.loglog(o, np.asarray(r["ours_rel_value"]).ravel(), ".", ms=3, color="tab:blue", alpha=0.6)
        if r.get("gens_value") is not None:
            ax.loglog(o, np.asarray(r["gens_value"]).ravel(), ".", ms=3, color="tab:orange", alpha=0.4)
    lim = ax.get_xlim()
    ax.plot(lim, lim, "k-", lw=0.7)
    ax.set_xlabel("Monte Carlo reduced radiance [sr^-1]")
    ax.set_ylabel("ours (blue), gensdaymtx / 400 nm (orange) [sr^-1]")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def save(res: dict, path: Path) -> None:
    from skyscatter.fileio import atomic_path

    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(res, indent=1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=int, default=20)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--pilot", type=int, default=512, help="pilot paths per direction and sky")
    ap.add_argument("--target", type=float, default=0.025, help="p90 relative standard error per hour")
    ap.add_argument("--max-samples", type=int, default=65536)
    ap.add_argument("--budget", type=float, default=50.0, help="Monte Carlo CPU minutes in all")
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "spectral_skymatrix_montecarlo.json")
    ap.add_argument("--radiance-dir", type=Path, default=None,
                    help="gensdaymtx's working folder (its atmos_data cache); default SKYSCATTER_CACHE_DIR/radiance")
    ap.add_argument("--until", default=None, help="UTC HH:MM: stop starting new Monte Carlo runs then")
    ap.add_argument("--kinds", default=",".join(KINDS),
                    help="comma-separated kinds of hours (clear, broken, overcast; low-sun hours by their kind) that "
                         "get Monte Carlo paths in this run; with --resume the others are carried from that file")
    ap.add_argument("--resume", type=Path, action="append", default=None,
                    help="an earlier results JSON (repeatable: per hour the row with the most paths): a sky "
                         "whose air is the same (retrieved optical depths, albedo, sun, patches) starts from its "
                         "paths (pooled with new seeds) instead of a pilot; its "
                         "gensdaymtx columns are reused (gensdaymtx is not run)")
    ap.add_argument("--chunk", type=int, default=8192,
                    help="most paths per direction in one Monte Carlo call (the budget is checked between calls)")
    ap.add_argument("--only", default=None, help="comma-separated hours of the year: only these get new paths")
    ap.add_argument("--subset", action="store_true",
                    help="with --resume: retrieve and compute our matrix on a record of the --kinds hours alone "
                         "(the first resumed file's picks), not the year (prepare_subset); other hours carried as "
                         "they are")
    ap.add_argument("--retrieval", type=Path, default=None,
                    help="pickle of the year's retrieval: read if it exists, else written (setup reuse)")
    ap.add_argument("--gens-calibrated", type=Path, default=None,
                    help="gensdaymtx with the year file's illuminance filled (Perez 1990) against a results JSON's "
                         "Monte Carlo; prints a table and exits")
    ap.add_argument("--regens", type=Path, default=None,
                    help="recompute gensdaymtx's columns of a results JSON (with its .jobs.pkl) and exit")
    ap.add_argument("--plot", type=Path, default=None, help="only redraw the figure and print the table of a JSON")
    ap.add_argument("--figure", type=Path, default=ROOT / "docs" / "images" / "spectral_skymatrix_montecarlo.png")
    args = ap.parse_args()
    if args.regens is not None:
        regens(args)
        return
    if args.gens_calibrated is not None:
        gens_calibrated(args)
        return
    if args.plot is not None:
        res = json.loads(args.plot.read_text())
        if gens_per_nm(res):
            save(res, args.plot)
            print(f"{args.plot}: gensdaymtx's columns put on the per-nm scale (/ {GENSDAYMTX_SPAN_NM:g})")
        plot(res, args.figure)
        print("\n".join(summarise(res)))
        print(f"wrote {args.figure}")
        return
    from skymatrix_mc import away_from_sun, matrix_directions, mc_reduced, patch_subset, pool
    from skyscatter.conventions import direction_from_angles

    c_start = time.process_time()
    w_start = time.perf_counter()
    stop = None
    if args.until:
        hh, mm = (int(x) for x in args.until.split(":"))
        now = time.gmtime()
        stop = time.time() + ((hh * 60 + mm) - (now.tm_hour * 60 + now.tm_min)) * 60.0 - now.tm_sec
    kinds = tuple(k.strip() for k in args.kinds.split(",") if k.strip())
    if not set(kinds) <= set(KINDS):
        ap.error(f"--kinds: one or more of {', '.join(KINDS)}")
    # per hour the earlier rows (and their files), most Monte Carlo paths first
    candidates: dict[int, list[tuple[dict, dict]]] = {}
    first = None
    resumed = []
    for path in args.resume or []:
        e = json.loads(path.read_text())
        gens_per_nm(e)
        e["file"] = str(path)
        first = first or e
        resumed.append(e)
        for r in e["hours"]:
            candidates.setdefault(int(r["hour"]), []).append((r, e))
    for c in candidates.values():
        c.sort(key=lambda x: -sum(s["paths"] for s in x[0]["skies"]))
    old_rows = bool(candidates)
    only = {int(x) for x in args.only.split(",")} if args.only else set()
    jobs_path = args.out.with_suffix(".jobs.pkl")
    if jobs_path.exists():
        setup = load_setup(jobs_path)
        print(f"setup read from {jobs_path}", flush=True)
    else:
        setup = (prepare_subset(args, first, kinds, only) if args.subset else
                 prepare(args, with_gens=not old_rows))
        jobs_path.write_bytes(pickle.dumps(setup))
    wl = np.array(WAVELENGTHS)
    res = {k: v for k, v in setup.items() if k not in ("jobs", "dirs")}
    res["gens_scale"] = "per nm"
    res["directions"] = "the matrix's evaluation point of each patch (one equal-area cell: mid sin(altitude))"
    res.update({"description": __doc__.split("\n\n")[0], "seed": args.seed, "wavelengths": list(WAVELENGTHS),
                "pilot": args.pilot, "target": args.target, "budget_cpu_min": args.budget, "until_utc": args.until,
                "kinds": list(kinds), "only_hours": args.only, "subset": args.subset, "chunk": args.chunk,
                "date_utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
                "resumed_from": [{k: e.get(k) for k in ("file", "date_utc", "until_utc", "kinds", "only_hours",
                                                        "budget_cpu_min", "mc_cpu_s", "load_average_start",
                                                        "load_average_now")} for e in resumed],
                "hours": [], "load_average_start": list(os.getloadavg())})
    # skies that get new paths in this run: the hours of --kinds; the others are carried from --resume as they are
    n_skies = sum(len(j["parts"]) for j in setup["jobs"] if j["kind"] in kinds and (not only or j["hour"] in only))
    dirs_all = matrix_directions()
    mc_cpu = 0.0
    skies_done = 0
    jobs_by_hour = {j["hour"]: j for j in setup["jobs"]}
    for pick in setup["picked"]:
        i = int(pick[0])
        job = jobs_by_hour.get(i)
        if job is None:  # not in this run's setup (--subset): the earlier row as it was
            if i in candidates:
                row, e = candidates[i][0]
                src = f"{e['file']} (run of {e.get('date_utc') or '2026-12-02'})"
                res["hours"].append({**row, "carried_verbatim_from": row.get("carried_verbatim_from", src)})
            continue
        kind, low = job["kind"], job["low_sun"]
        # this run adds paths to the hour's skies (a zero budget only gathers earlier runs)
        run_here = kind in kinds and (not only or i in only) and args.budget > 0
        # the earlier row whose skies all ran through this job's air (most paths first), else the first one
        rows_i = candidates.get(i, [])
        match = [x for x in rows_i if all(same_sky(x[0], what, job, patch_subset(dirs_all, job["sun_azimuth"]))
                                          is not None for _, what, _ in job["parts"])]
        old, earlier = (match or rows_i or [(None, None)])[0]
        if not run_here and not match:
            print(f"hour {i} ({kind}) left out: no Monte Carlo through its air in "
                  f"{[str(p) for p in args.resume or []]}", flush=True)
            continue
        zen, azi = job["sun_zenith"], job["sun_azimuth"]
        sun = direction_from_angles(zen, azi)
        dirs = dirs_all
        patches = patch_subset(dirs, azi)
        pd = dirs[patches]
        r_mc = np.zeros((patches.size, wl.size))
        var_mc = np.zeros_like(r_mc)
        away = np.ones(patches.size, bool)
        info = []
        carried_all = True
        for part, (w, what, air) in enumerate(job["parts"]):
            if stop is not None and time.time() > stop:
                break
            seed0 = 1000 * i + 10 * part
            prior = same_sky(old, what, job, patches) if old is not None else None
            if prior is None and not run_here:
                break
            if prior is not None:
                est = (np.asarray(prior["mc_rel"]), np.asarray(prior["mc_rel_se"]), int(prior["paths"]))
                runs = runs_of(prior, seed0, earlier)
                c = float(prior["cpu_s"])
                c_here = 0.0
            else:
                w0 = time.perf_counter()
                m, s, n, c_here = mc_reduced(air, pd, wl, zen, azi, args.pilot, seed0)
                est, c = (m, s, n), c_here
                runs = [{"seed": seed0, "paths": n, "cpu_s": c_here, "wall_s": time.perf_counter() - w0,
                         "run_utc": res["date_utc"]}]
            if run_here:
                left_skies = max(n_skies - skies_done, 1)
                allowance = (args.budget * 60.0 - mc_cpu) / left_skies  # this sky's share of the CPU left
                spent = c_here
                while True:
                    rel = float(np.percentile(est[1] / est[0], 90))
                    n = est[2]
                    want = int(n * (rel / args.target) ** 2) - n
                    per_path = c / max(n, 1)
                    afford = int((allowance - spent) / max(per_path, 1e-9))
                    if stop is not None:  # wall clock: the machine is shared, a CPU budget alone would overrun
                        timed = [r for r in runs if r.get("wall_s") is not None]
                        # wall seconds per path of this run's calls; before the first, a quarter core assumed
                        wall_path = (sum(r["wall_s"] for r in timed) / sum(r["paths"] for r in timed) if timed
                                     else per_path * 4.0)
                        afford = min(afford, int((stop - time.time()) / max(left_skies, 1) / max(wall_path, 1e-9)))
                    extra = int(min(want, afford, args.max_samples - n, args.chunk))
                    if extra < 256:
                        break
                    seed = max(r["seed"] for r in runs) + 1
                    w0 = time.perf_counter()
                    m2, s2, n2, c2 = mc_reduced(air, pd, wl, zen, azi, extra, seed)
                    runs.append({"seed": seed, "paths": n2, "cpu_s": c2, "wall_s": time.perf_counter() - w0,
                                 "run_utc": res["date_utc"]})
                    mc_cpu += c2
                    spent += c2
                    c += c2
                    est = pool(est, (m2, s2, n2))
                    print(f"  hour {i} {what}: {est[2]} paths, p90 SE {np.percentile(est[1] / est[0], 90) * 100:.2f} %"
                          f" ({c2:.0f} CPU-s)", flush=True)
                mc_cpu += c_here
                skies_done += 1
            carried_all &= prior is not None and len(runs) == len(runs_of(prior, seed0, earlier))
            r_mc += w * est[0]
            var_mc += (w * est[1]) ** 2
            away &= away_from_sun(pd, sun, what)
            info.append({"sky": what, "weight": w, "paths": int(est[2]), "cpu_s": c, "runs": runs,
                         "p90_rel_se": float(np.percentile(est[1] / est[0], 90)),
                         "patches_all": patches.tolist(), "mc_rel": est[0].tolist(), "mc_rel_se": est[1].tolist()})
        if len(info) < len(job["parts"]):
            print(f"stopped at {args.until} UTC before hour {i} was finished", flush=True)
            break
        se_mc = np.sqrt(var_mc)
        r_ours = job["ours"][patches]
        row = {"hour": i, "kind": kind, "low_sun": low, "sun_zenith_deg": float(np.degrees(zen)),
               "sun_azimuth_deg": float(np.degrees(azi)), **job["meta"],
               "patches": patches[away].tolist(), "skies": info,
               "mc_carried": bool(carried_all),
               "mc_rel": r_mc[away].tolist(), "mc_rel_se": (se_mc / r_mc)[away].tolist(),
               "ours_rel_value": r_ours[away].tolist(), "ours_rel": (r_ours / r_mc - 1)[away].tolist()}
        gens = job["gens"][patches][away] if job["gens"] is not None else None
        if gens is None and old is not None and old.get("gens_value") is not None \
                and list(old["patches"]) == row["patches"]:
            gens = np.asarray(old["gens_value"])  # gensdaymtx on the same file: the same bytes, unchanged
        if gens is not None:
            ratio = gens / r_mc[away]
            scale = float(np.median(ratio))
            row.update({"gens_value": gens.tolist(), "gens_rel": (ratio - 1).tolist(),
                        "gens_median_ratio": scale, "gens_shape_rel": (ratio / scale - 1).tolist()})
        res["hours"].append(row)
        res["mc_cpu_s"] = mc_cpu
        res["cpu_s_total"] = time.process_time() - c_start
        res["wall_s_total"] = time.perf_counter() - w_start
        res["load_average_now"] = list(os.getloadavg())
        save(res, args.out)
        o = np.asarray(row["ours_rel"])
        print(f"{kind:8s}{' low' if low else '    '} hour {i:5d} zenith {row['sun_zenith_deg']:5.1f}: "
              + " + ".join(f"{x['sky']} {x['paths']} paths {x['cpu_s']:.0f} s" for x in info) + "; ours median "
              f"{np.median(o) * 100:+.1f} %, p95 |.| {np.percentile(abs(o), 95) * 100:.1f} %, MC SE median "
              f"{np.median(row['mc_rel_se']) * 100:.1f} %" + (" (carried)" if carried_all else "")
              + (f"; gensdaymtx ratio {row['gens_median_ratio']:.3g}, shape p95 "
                 f"{np.percentile(np.abs(row['gens_shape_rel']), 95) * 100:.1f} %" if gens is not None
                 else ""), flush=True)
    if res["hours"]:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cloudysky_columns(res, setup)
        save(res, args.out)
        print("\n".join(summarise(res)))
        plot(res, args.figure)
    print(f"Monte Carlo CPU {mc_cpu:.0f} s; wrote {args.out}, {args.figure}; load average {os.getloadavg()}")


def runs_of(sky: dict, seed0: int, earlier: dict) -> list[dict]:
    """The seeded runs of a results JSON's sky: its own ``runs``, or (files written before 2026-12-04) the pilot of
    ``earlier["pilot"]`` paths at ``seed0`` and the follow-up of the rest at ``seed0 + 1`` (what this script ran)."""
    if "runs" in sky:
        return [dict(r) for r in sky["runs"]]
    pilot = int(earlier["pilot"])
    when = earlier.get("date_utc", "2026-12-02 08:10")
    runs = [{"seed": seed0, "paths": min(pilot, int(sky["paths"])), "cpu_s": None, "run_utc": when}]
    if int(sky["paths"]) > pilot:
        runs.append({"seed": seed0 + 1, "paths": int(sky["paths"]) - pilot, "cpu_s": None, "run_utc": when})
    return runs


def phase_g(ds, h, i: int) -> float:
    """The phase g of hour ``i``'s clear air as the Monte Carlo takes it (``skymatrix_mc.parts_of``): the matrix's
    ``aerosol_phase_g``, the family base's where NaN or absent (a particle aerosol has no such axis)."""
    base = float(h.family.base.mie_phase_g) if h.family is not None else np.nan
    g = float(ds["aerosol_phase_g"].values[i]) if "aerosol_phase_g" in ds else np.nan
    return g if np.isfinite(g) else base


def same_sky(old: dict, what: str, job: dict, patches: np.ndarray) -> dict | None:
    """The sky ``what`` of an earlier results row when its Monte Carlo ran through the air this job's would (the
    same retrieved aerosol optical depth, albedo and phase g, cloud optical depth and sun, the same patches), else
    None. A row written before the retrieval had a phase leg (2026-12-02) has no ``aerosol_phase_g``: its clear
    sky ran through the base medium's g (``meta["base_phase_g"]``)."""
    sky = next((s for s in old["skies"] if s["sky"] == what), None)
    if sky is None or list(sky["patches_all"]) != patches.tolist():
        return None
    keys = ("aod", "ssa", "aerosol_phase_g") if what == "clear" else ("cloud_optical_depth",)
    for k in keys:
        # a row without the phase's g ran before the retrieval's phase leg: through the base medium's g
        a, b = float(old.get(k, job["meta"].get("base_phase_g", np.nan))), float(job["meta"].get(k, np.nan))
        if not (np.isclose(a, b, rtol=1e-9, atol=0.0) or (np.isnan(a) and np.isnan(b))):
            return None
    if not np.isclose(old["sun_zenith_deg"], np.degrees(job["sun_zenith"]), rtol=0, atol=1e-9):
        return None
    return sky

def gens_reduced(epw: Path, hours: list[int], cache: Path | None) -> dict[int, np.ndarray]:
    """gensdaymtx's patches of ``hours`` per nm (over :data:`GENSDAYMTX_SPAN_NM`), over its bands' E0 and the
    eccentricity (145, 4) [sr^-1]."""
    from skymatrix_mc import band_e0
    from skyscatter.fit.spectral_matrix import band_edges

    c20, edges20 = band_edges(20)
    b_wl = [int(np.argmin(np.abs(c20 - w))) for w in WAVELENGTHS]
    e0 = band_e0(edges20, b_wl)
    gens = gensdaymtx_matrix(epw, cache)
    from skyscatter.fit.weather import read_weather
    from skyscatter.sky.perez import SOLAR_CONSTANT, extraterrestrial_irradiance

    ecc = np.asarray(extraterrestrial_irradiance(read_weather(epw).day_of_year), dtype=float) / SOLAR_CONSTANT
    return {i: gens[i][:, b_wl] / (GENSDAYMTX_SPAN_NM * e0 * ecc[i]) for i in hours}


def with_illuminance(src: Path, out: Path) -> Path:
    """Copy of the EPW ``src`` with its illuminance fields (17-19: global, direct normal, diffuse horizontal [lx])
    filled from its irradiance by Perez et al. (1990)'s luminous efficacies (Table 4, ``sky.perez.luminous_efficacy``;
    sky clearness and brightness from DNI and DHI, the file's precipitable water): gensdaymtx scales its sky to the
    diffuse illuminance, and a file without it (missing, 999999) leaves its sky uncalibrated."""
    from skyscatter.fit.weather import read_weather
    from skyscatter.sky.perez import luminous_efficacy, sky_brightness, sky_clearness
    from skyscatter.sun.position import sun_position_unix

    rec = read_weather(src)
    zen = np.asarray(sun_position_unix(rec.location.latitude, rec.location.longitude, rec.unix_times(),
                                       apparent=False).zenith)
    ghi, dni, dhi = (rec.global_horizontal_irradiance, rec.direct_normal_irradiance,
                     rec.diffuse_horizontal_irradiance)
    # the record's precipitable water is in mm; Perez's W in cm
    water = rec.precipitable_water / 10.0 if rec.precipitable_water is not None else np.full(ghi.size, 1.4)
    ok = (dhi > 0) & (zen < np.radians(89.5))
    eps = np.where(ok, sky_clearness(dni, np.where(ok, dhi, 1.0), zen), 1.0)
    delta = np.maximum(np.where(ok, sky_brightness(np.where(ok, dhi, 0.0), zen, rec.day_of_year), 0.1), 1e-3)
    k = {kind: luminous_efficacy(kind, eps, delta, zen, water) for kind in ("global", "direct", "diffuse")}
    lines = src.read_text().splitlines()
    head, body = lines[:8], lines[8:]
    for j in np.flatnonzero(ok):
        f = body[j].split(",")
        f[16], f[17], f[18] = (f"{k['global'][j] * ghi[j]:.0f}", f"{k['direct'][j] * dni[j]:.0f}",
                               f"{k['diffuse'][j] * dhi[j]:.0f}")
        body[j] = ",".join(f)
    out.write_text("\n".join(head + body) + "\n")
    return out


def gens_calibrated(args) -> None:
    """gensdaymtx on the year file with illuminance (:func:`with_illuminance`), its patches per nm against the
    Monte Carlo of a results JSON (patches and wavelengths pooled per kind of hour); prints a table."""
    from weather_synth import write_year_epw

    res = json.loads(args.gens_calibrated.read_text())
    work = Path(tempfile.mkdtemp(prefix="mc-spectral-"))
    epw = with_illuminance(write_year_epw(work / "year.epw"), work / "year_illum.epw")
    t0 = time.perf_counter()
    g = gens_reduced(epw, [int(r["hour"]) for r in res["hours"]], args.radiance_dir)
    print(f"gensdaymtx -m 1 -s (illuminance filled): {time.perf_counter() - t0:.0f} s")
    groups = [("clear", lambda r: r["kind"] == "clear" and not r["low_sun"]),
              ("broken", lambda r: r["kind"] == "broken" and not r["low_sun"]),
              ("overcast", lambda r: r["kind"] == "overcast" and not r["low_sun"]),
              ("low sun (70-86 deg)", lambda r: r["low_sun"]), ("all", lambda r: True)]
    print("| hours | n | gensdaymtx calibrated vs MC: median | median abs | p95 abs |\n|---|---|---|---|---|")
    for name, sel in groups:
        hs = [r for r in res["hours"] if sel(r)]
        rel = np.concatenate([(g[r["hour"]][r["patches"]] / np.asarray(r["mc_rel"]) - 1).ravel() for r in hs])
        rel = rel[np.isfinite(rel)]
        print(f"| {name} | {len(hs)} | {np.median(rel) * 100:+.1f} % | {np.median(np.abs(rel)) * 100:.1f} % | "
              f"{np.percentile(np.abs(rel), 95) * 100:.1f} % |")


def regens(args) -> None:
    """Redo gensdaymtx's columns of a results JSON (the year file is made again: same seed, same bytes)."""
    from weather_synth import write_year_epw

    res = json.loads(args.regens.read_text())
    cache = args.regens.with_suffix(".gens-per-nm.npz")
    if cache.exists():
        with np.load(cache) as z:
            g = {int(k): z[k] for k in z.files}
    else:
        epw = write_year_epw(Path(tempfile.mkdtemp(prefix="mc-spectral-")) / "year.epw")
        t0 = time.perf_counter()
        g = gens_reduced(epw, [int(p[0]) for p in res["picked"]], args.radiance_dir)
        print(f"gensdaymtx -m 1 -s: {time.perf_counter() - t0:.0f} s")
        np.savez(cache, **{str(k): v for k, v in g.items()})
    for row in res["hours"]:
        r_g = g[row["hour"]][row["patches"]]
        ratio = r_g / np.asarray(row["mc_rel"])
        scale = float(np.median(ratio))
        row.update({"gens_value": r_g.tolist(), "gens_rel": (ratio - 1).tolist(), "gens_median_ratio": scale,
                    "gens_shape_rel": (ratio / scale - 1).tolist(), "gens_options": "-m 1 -s"})
    res["gens_scale"] = "per nm"
    cloudysky_columns(res, load_setup(args.regens.with_suffix(".jobs.pkl")))
    save(res, args.regens)


def load_setup(path: Path) -> dict:
    from skyscatter.atmosphere.clouds import CloudLayer

    # CloudLayer refuses attribute assignment, which pickle's default state restore uses: allow it while loading
    guard = CloudLayer.__setattr__
    CloudLayer.__setattr__ = object.__setattr__
    try:
        return pickle.loads(path.read_bytes())
    finally:
        CloudLayer.__setattr__ = guard


def cloudysky_columns(res: dict, setup: dict) -> None:
    """For hours with an overcast part: CloudySky (DISORT, the model the matrix's overcast patches follow) at the
    hour's exact optical depth and sun against that part's Monte Carlo (``cloudysky_vs_mc``), and ours against
    the blend with CloudySky in place of the overcast Monte Carlo (``ours_vs_cloudysky_blend``): which of the two
    steps (matrix vs its model, model vs the reference) a difference comes from."""
    from skymatrix_mc import matrix_directions
    from skyscatter.sky.cloudy import CloudySky

    wl = np.array(res["wavelengths"])
    dirs = matrix_directions()
    jobs = {j["hour"]: j for j in setup["jobs"]}
    for row in res["hours"]:
        if row["hour"] not in jobs or row.get("carried_verbatim_from"):
            continue  # an earlier run's row kept as it was (its columns with it)
        parts = {s["sky"]: s for s in row["skies"]}
        if "overcast" not in parts or "mc_rel" not in parts["overcast"]:
            continue
        job = jobs[row["hour"]]
        air = [a for _, what, a in job["parts"] if what == "overcast"][0]
        air = air.replace(particles=air.particles[:-1])
        pa = np.asarray(parts["overcast"]["patches_all"])
        keep = np.isin(pa, row["patches"])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sky = CloudySky(job["sun_zenith"], job["sun_azimuth"], cloud_optical_depth=row["cloud_optical_depth"],
                            atmosphere=air)
            cs = sky.spectral_radiance(dirs[pa], wl) / air.solar_irradiance_at(wl)
        mc_o = np.asarray(parts["overcast"]["mc_rel"])
        f = parts["overcast"]["weight"]
        blend = f * cs + ((1 - f) * np.asarray(parts["clear"]["mc_rel"]) if "clear" in parts else 0.0)
        row["cloudysky_vs_mc"] = (cs / mc_o - 1)[keep].tolist()
        row["ours_vs_cloudysky_blend"] = (job["ours"][pa] / blend - 1)[keep].tolist()


def prepare(args, with_gens: bool = True) -> dict:
    """Retrieval, our matrix and gensdaymtx's (unless not ``with_gens``) on the made year; per picked hour the
    reduced patch radiances of both (all 145 patches, the 4 wavelengths) and the Monte Carlo skies (weight, kind,
    air). Our matrix is computed for the picked hours only (every other hour given the night's status: the matrix
    computes each hour from its own retrieved atmosphere)."""
    import dataclasses

    from skymatrix_mc import band_e0, parts_of
    from skyscatter.fit.spectral_matrix import band_edges, spectral_sky_matrix
    from skyscatter.fit.weather import HOUR_STATUS, retrieve_hourly_atmosphere
    from skyscatter.patches import patch_scheme
    from weather_synth import write_year_epw

    w_start = time.perf_counter()
    work = Path(tempfile.mkdtemp(prefix="mc-spectral-"))
    epw = write_year_epw(work / "year.epw")
    if args.retrieval is not None and args.retrieval.exists():
        h = load_setup(args.retrieval)
        print(f"retrieval read from {args.retrieval}", flush=True)
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            h = retrieve_hourly_atmosphere(epw)
        if args.retrieval is not None:
            args.retrieval.write_bytes(pickle.dumps(h))
    counts = {HOUR_STATUS[k]: int((h.status == k).sum()) for k in HOUR_STATUS}
    print(f"retrieval: {counts} ({time.perf_counter() - w_start:.0f} s)", flush=True)
    picks = pick_hours(h, args.hours, args.seed)
    geom = patch_scheme("tregenza")
    wl = np.array(WAVELENGTHS)
    centres = [w + d for w in WAVELENGTHS for d in (-5.0, 0.0, 5.0)]
    k_ours = [1 + 3 * j for j in range(len(WAVELENGTHS))]
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        picked = np.zeros(h.status.size, bool)
        picked[[p[0] for p in picks]] = True
        only = dataclasses.replace(h, status=np.where(picked, h.status, 0))
        ds = spectral_sky_matrix(None, scheme=geom, samples=1, bands=centres, atmosphere=only, gases=False)
    t_ours = time.perf_counter() - t0
    print(f"our matrix (Tregenza, {len(centres)} bands, the {len(picks)} hours): {t_ours:.1f} s", flush=True)
    _, edges5 = band_edges(centres)
    e0_ours = band_e0(edges5, k_ours)
    c20, edges20 = band_edges(20)
    b_wl = [int(np.argmin(np.abs(c20 - w))) for w in wl]
    e0_gens = band_e0(edges20, b_wl)
    t0 = time.perf_counter()
    try:
        if not with_gens:
            raise RuntimeError("not run: its columns come from --resume")
        gens = gensdaymtx_matrix(epw, args.radiance_dir)
        print(f"gensdaymtx -m 1 (the whole year): {time.perf_counter() - t0:.1f} s", flush=True)
    except Exception as exc:  # noqa: BLE001 - the peer is optional
        print(f"gensdaymtx skipped: {exc}")
        gens = None
    jobs = []
    for i, kind, low in picks:
        ecc = float(h.eccentricity[i])
        jobs.append({"hour": i, "kind": kind, "low_sun": low, "sun_zenith": float(h.sun_zenith[i]),
                     "sun_azimuth": float(h.sun_azimuth[i]), "parts": parts_of(h, ds, i, kind),
                     "ours": ds["sky_radiance"].values[i][:, k_ours] / (e0_ours * ecc),
                     "gens": None if gens is None else gens[i][:, b_wl] / (GENSDAYMTX_SPAN_NM * e0_gens * ecc),
                     "meta": {"aod": float(h.aerosol_optical_depth[i]),
                              "ssa": float(ds["single_scattering_albedo"].values[i]),
                              "aerosol_phase_g": phase_g(ds, h, i),
                              "base_phase_g": phase_g({}, h, 0),
                              "cloud_optical_depth": float(h.cloud_optical_depth[i]),
                              "cloud_fraction": float(h.cloud_fraction[i]), "status": HOUR_STATUS[int(h.status[i])],
                              "dhi_closure": float(ds["dhi_closure"].values[i])}})
    return {"epw": "tests/weather_synth.py write_year_epw seed 24", "retrieval_counts": counts,
            "picked": [list(p) for p in picks], "our_matrix_seconds": t_ours,
            "setup_wall_s": time.perf_counter() - w_start, "jobs": jobs}



def prepare_subset(args, earlier: dict, kinds: tuple[str, ...], only: set[int]) -> dict:
    """:func:`prepare` for the hours of ``kinds`` (and ``only``, when given) among ``earlier``'s picks, on a
    record of those hours alone: the year's retrieval needs the whole table family (36 tables by default), which
    overcast hours do not use. The same as the year's for overcast hours when the hours' aerosol comes from the
    file's field in both (no clear hour on their day: checked against ``earlier``'s ``aod``) and the cloud table's
    aerosol node is the same (the node nearest the median of the cloudy hours' aerosol). Not for clear or broken
    hours (their skies come from the family's tables; refused)."""
    from skymatrix_mc import band_e0, parts_of
    from skyscatter.fit.spectral_matrix import band_edges, spectral_sky_matrix
    from skyscatter.fit.weather import HOUR_STATUS, retrieve_hourly_atmosphere
    from skyscatter.patches import patch_scheme
    from weather_synth import write_year_epw

    if set(kinds) != {"overcast"}:
        raise SystemExit("--subset: overcast hours only (clear and broken hours need the year's table family)")
    w_start = time.perf_counter()
    picks = [tuple(p) for p in earlier["picked"] if p[1] in kinds and (not only or int(p[0]) in only)]
    hours = sorted(int(p[0]) for p in picks)
    work = Path(tempfile.mkdtemp(prefix="mc-spectral-"))
    lines = write_year_epw(work / "year.epw").read_text().splitlines()
    sub = work / "hours.epw"
    sub.write_text("\n".join(lines[:8] + [lines[8 + i] for i in hours]) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h = retrieve_hourly_atmosphere(sub)
    rows = {int(r["hour"]): r for r in earlier["hours"]}
    for j, i in enumerate(hours):
        if h.aerosol_source[j] != "file" or (i in rows and not np.isclose(h.aerosol_optical_depth[j], rows[i]["aod"])):
            raise SystemExit(f"--subset: hour {i}'s aerosol ({h.aerosol_source[j]}) is not the year's")
    print(f"retrieval of the {len(hours)} hours: {time.perf_counter() - w_start:.0f} s; {h.notes}", flush=True)
    geom = patch_scheme("tregenza")
    centres = [w + d for w in WAVELENGTHS for d in (-5.0, 0.0, 5.0)]
    k_ours = [1 + 3 * j for j in range(len(WAVELENGTHS))]
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = spectral_sky_matrix(None, scheme=geom, samples=1, bands=centres, atmosphere=h, gases=False)
    t_ours = time.perf_counter() - t0
    _, edges5 = band_edges(centres)
    e0_ours = band_e0(edges5, k_ours)
    jobs = []
    for i, kind, low in picks:
        j = hours.index(int(i))
        ecc = float(h.eccentricity[j])
        jobs.append({"hour": int(i), "kind": kind, "low_sun": low, "sun_zenith": float(h.sun_zenith[j]),
                     "sun_azimuth": float(h.sun_azimuth[j]), "parts": parts_of(h, ds, j, kind),
                     "ours": ds["sky_radiance"].values[j][:, k_ours] / (e0_ours * ecc), "gens": None,
                     "meta": {"aod": float(h.aerosol_optical_depth[j]),
                              "ssa": float(ds["single_scattering_albedo"].values[j]),
                              "aerosol_phase_g": phase_g(ds, h, j),
                              "base_phase_g": phase_g({}, h, 0),
                              "cloud_optical_depth": float(h.cloud_optical_depth[j]),
                              "cloud_fraction": float(h.cloud_fraction[j]), "status": HOUR_STATUS[int(h.status[j])],
                              "dhi_closure": float(ds["dhi_closure"].values[j])}})
    return {"epw": "tests/weather_synth.py write_year_epw seed 24", "retrieval_counts": earlier["retrieval_counts"],
            "picked": earlier["picked"], "our_matrix_seconds": t_ours, "setup_wall_s": time.perf_counter() - w_start,
            "setup": f"--subset: retrieval and matrix on a record of the hours {hours} alone ({h.notes})",
            "jobs": jobs}


if __name__ == "__main__":
    main()
