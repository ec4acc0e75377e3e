"""Diagnosis of the precomputed tables' low-sun error against the Monte Carlo reference (issue 23).

Splits the table radiance into single scattering (Rayleigh + Mie, phase applied at lookup) and multiple
scattering, and compares:

* the tables' single scattering with an independent Gauss-Legendre integral (``tests/precomputed_reference``,
  plain numpy, point sun);
* the tables' multiple scattering with the Monte Carlo total minus that integral;

at sun elevations on sun-zenith texels and between them, so that the interpolation of the lookup along the sun
zenith shows apart from the errors of the precomputation itself.

``python benchmarks/diagnose_low_sun.py [--samples N] [--sizes mu_s=64,...] [--atm hazy|earth|aod05]``
"""

from __future__ import annotations

import argparse
import importlib
import math
import pathlib
import sys
import time

import numpy as np

from skyscatter.montecarlo import sky_radiance
from skyscatter.precomputed import AtmosphereParameters, PrecomputedAtmosphere, cached_atmosphere
from skyscatter.precomputed.kernels import mu_s_texels

_TESTS = pathlib.Path(__file__).resolve().parents[1] / "tests"


def reference_module():
    """tests/precomputed_reference.py (it imports its sibling tests/quadrature.py, so tests/ goes on the path)."""
    sys.path.insert(0, str(_TESTS))
    try:
        return importlib.import_module("precomputed_reference")
    finally:
        sys.path.remove(str(_TESTS))


def atmospheres() -> dict[str, AtmosphereParameters]:
    return {
        "earth": AtmosphereParameters(),
        "hazy": AtmosphereParameters.from_turbidity(3.0),
        "aod05": AtmosphereParameters.from_aerosol_optical_depth(0.5),
    }


def view_directions(elevations, azimuths):
    out, labels = [], []
    for az in azimuths:
        for el in elevations:
            e, a = math.radians(el), math.radians(az)
            out.append([math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)])
            labels.append((el, az))
    return np.array(out), labels


def cached_mc(params, dirs, wl, zen, samples, tag):
    """Monte Carlo radiance and stderr (seed 1), kept in $SKYSCATTER_CACHE_DIR/diagnose_mc between runs."""
    import os
    folder = pathlib.Path(os.environ.get("SKYSCATTER_CACHE_DIR", ".")) / "diagnose_mc"
    folder.mkdir(parents=True, exist_ok=True)
    f = folder / f"{tag}_{samples}.npz"
    if f.exists():
        d = np.load(f)
        return d["radiance"][:, 0], d["stderr"][:, 0]
    mc = sky_radiance(params, dirs, wl, sun_zenith=zen, samples=samples, seed=1)
    np.savez(f, radiance=mc.radiance, stderr=mc.stderr)
    return mc.radiance[:, 0], mc.stderr[:, 0]


def catmull_rom_weights(t):
    return np.stack([0.5 * (-t + 2 * t * t - t ** 3), 0.5 * (2 - 5 * t * t + 3 * t ** 3),
                     0.5 * (t + 4 * t * t - 3 * t ** 3), 0.5 * (-t * t + t ** 3)], axis=-1)


def manual_lookup(atm, dirs, sun, cubic_tables):
    """Observer on the ground: (single, multiple) radiance with linear mu and linear or cubic nu per table."""
    from skyscatter.atmosphere.phase import aerosol_phase_scalar, rayleigh_phase_scalar
    from skyscatter.precomputed.geometry import scattering_nu_coord, scattering_r_mu_coord
    from skyscatter.precomputed.lookup import observer_slices

    p = atm.parameters
    rb, rt = p.bottom_radius, p.top_radius
    nl = atm.wavelengths.size
    sl = observer_slices(atm.tables["single_rayleigh"], atm.tables["single_mie"], atm.tables["multiple"], rb,
                         float(sun[2]), rb, rt, p.mu_s_min, 0, np.eye(nl))[0]  # stored (unsplit) axis; on the ground
    n_mu, n_nu = sl.shape[:2]
    out_s, out_m = [], []
    for d in dirs:
        mu, nu = float(d[2]), float(d @ sun)
        _, pm = scattering_r_mu_coord(rb, mu, False, rb, rt, atm.sizes.scattering_r, n_mu)
        i = min(max(int(pm), n_mu // 2), n_mu - 2)
        wm = pm - i
        pn = scattering_nu_coord(mu, float(sun[2]), nu, n_nu)
        j = min(int(pn), n_nu - 2)
        wn = pn - j
        vals = []
        for c in range(3):
            row = (1 - wm) * sl[i, :, :, c] + wm * sl[i + 1, :, :, c]  # (n_nu, nl)
            if c in cubic_tables:
                idx = np.array([j - 1, j, j + 1, j + 2])
                idx = np.where(idx < 0, -idx, idx)
                idx = np.where(idx > n_nu - 1, 2 * (n_nu - 1) - idx, idx)
                v = catmull_rom_weights(wn) @ row[idx]
            else:
                v = (1 - wn) * row[j] + wn * row[j + 1]
            vals.append(v)
        pr = rayleigh_phase_scalar(nu)
        pmie = aerosol_phase_scalar(nu, p.mie_phase_g, atm._mie_kind)
        out_s.append(vals[0] * pr + vals[1] * pmie)
        out_m.append(vals[2])
    return np.array(out_s)[:, 0], np.array(out_m)[:, 0]


def split(atm: PrecomputedAtmosphere) -> tuple[PrecomputedAtmosphere, PrecomputedAtmosphere]:
    """(single only, multiple only) copies of the tables. The single-only copy keeps ``computed`` (so that its
    lookups compute the single scattering's sub-texels of the refined sun-zenith axis from the atmosphere, as the
    whole tables' do); the multiple-only copy does not (it would compute single scattering there)."""
    t = dict(atm.tables)
    zero = np.zeros_like(t["multiple"])
    single = PrecomputedAtmosphere(atm.parameters, atm.wavelengths, atm.sizes, atm.orders, {**t, "multiple": zero},
                                   computed=atm.computed)
    mult = PrecomputedAtmosphere(atm.parameters, atm.wavelengths, atm.sizes, atm.orders,
                                 {**t, "single_rayleigh": zero, "single_mie": zero})
    return single, mult


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=2048)
    ap.add_argument("--atm", default="hazy", choices=sorted(atmospheres()))
    ap.add_argument("--sizes", default="", help="table size overrides, e.g. scattering_mu_s=64,scattering_nu=16")
    ap.add_argument("--wavelength", type=float, default=550.0)
    ap.add_argument("--subsample-nu", type=int, default=1, help="keep every k-th azimuth texel (lookup only)")
    ap.add_argument("--cubic-nu", default="", help="tables (0 1 2) interpolated by Catmull-Rom along nu")
    ap.add_argument("--fresh", action="store_true", help="compute the tables (no cache): for code experiments")
    ap.add_argument("--suns", default="texel", help="'texel' (texel and mid-cell elevations) or a list in deg")
    ap.add_argument("--elevations", default="2,5,10")
    ap.add_argument("--azimuths", default="0,22.5,45,90,180")
    args = ap.parse_args()
    params = atmospheres()[args.atm]
    sizes = dict(kv.split("=") for kv in args.sizes.split(",") if kv)
    sizes = {k: int(v) for k, v in sizes.items()}
    wl = np.array([args.wavelength])
    t0 = time.perf_counter()
    if args.fresh:
        atm = PrecomputedAtmosphere.compute(params, wavelengths=wl, sizes=sizes or None, progress=False)
    else:
        atm = cached_atmosphere(params, wavelengths=wl, sizes=sizes or None, progress=False)
    print(f"# tables {atm.sizes.scattering_shape} at {wl[0]:g} nm: {time.perf_counter() - t0:.1f} s", flush=True)
    if args.subsample_nu > 1:
        k = args.subsample_nu
        import dataclasses
        n_nu = (atm.sizes.scattering_nu - 1) // k + 1
        sz2 = dataclasses.replace(atm.sizes, scattering_nu=n_nu)
        tabs = dict(atm.tables)
        for name in ("single_rayleigh", "single_mie", "multiple"):
            tabs[name] = np.ascontiguousarray(tabs[name][:, :, :, ::k])
        atm = PrecomputedAtmosphere(atm.parameters, atm.wavelengths, sz2, atm.orders, tabs)
        print(f"# subsampled to {atm.sizes.scattering_shape}")
    single, mult = split(atm)
    ref = reference_module()
    if args.suns == "texel":
        tex = np.degrees(np.arcsin(mu_s_texels(params.bottom_radius, params.top_radius, params.mu_s_min,
                                               atm.sizes.scattering_mu_s)))
        pick = [e for e in tex if -4.0 <= e <= 12.0]
        suns = []
        for a, b in zip(pick[:-1], pick[1:], strict=False):
            suns += [a, 0.5 * (a + b)]
        suns.append(pick[-1])
    else:
        suns = [float(s) for s in args.suns.split(",")]
    dirs, labels = view_directions([float(x) for x in args.elevations.split(",")],
                                   [float(x) for x in args.azimuths.split(",")])
    pos = np.array([0.0, 0.0, params.bottom_radius])
    print("| sun el | kind | " + " | ".join(f"{el:g}/{az:g}" for el, az in labels) + " |")
    print("|---|---|" + "---|" * len(labels))
    for se in suns:
        zen = math.radians(90.0 - se)
        sun = np.array([0.0, math.sin(zen), math.cos(zen)])
        tab = atm.sky_radiance(pos, dirs, sun)[:, 0]
        tab_s = single.sky_radiance(pos, dirs, sun)[:, 0]
        tab_m = mult.sky_radiance(pos, dirs, sun)[:, 0]
        if args.cubic_nu:
            tab_s, tab_m = manual_lookup(atm, dirs, sun, [int(c) for c in args.cubic_nu])
            tab = tab_s + tab_m
        tag = f"{args.atm}_{se:.2f}_{args.wavelength:g}_{args.elevations}_{args.azimuths}"
        mc = cached_mc(params, dirs, wl, zen, args.samples, tag)
        ref_s = np.array([ref.single_scattering(params.bottom_radius, d[2], sun[2], float(d @ sun), params, wl)[0]
                          for d in dirs]) if se > -8 else np.full(len(dirs), np.nan)
        mc_v, mc_e = mc
        rows = {
            "total tab/MC-1 [%]": [f"{100 * (a / b - 1):+.1f}±{100 * e / b:.1f}" for a, b, e in zip(tab, mc_v, mc_e,
                                                                                                  strict=True)],
            "single tab/ref-1 [%]": [f"{100 * (a / b - 1):+.1f}" for a, b in zip(tab_s, ref_s, strict=True)],
            "mult tab/(MC-ref)-1 [%]": [f"{100 * (a / (b - c) - 1):+.1f}±{100 * e / (b - c):.1f}"
                                        for a, b, c, e in zip(tab_m, mc_v, ref_s, mc_e, strict=True)],
            "MC mult (x1e3 of MC at first dir)": [f"{1e3 * (b - c) / mc_v[0]:.1f}"
                                                  for b, c in zip(mc_v, ref_s, strict=True)],
            "tab / MC abs": [f"{a:.4g}/{b:.4g}" for a, b in zip(tab, mc_v, strict=True)],
            "mult share of MC [%]": [f"{100 * (b - c) / b:.0f}" for b, c in zip(mc_v, ref_s, strict=True)],
        }
        for kind, cells in rows.items():
            print(f"| {se:+.2f} | {kind} | " + " | ".join(cells) + " |", flush=True)
    print(f"# {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
