"""Where the variance of the overcast reference is, and estimators against it: alternating A/B runs of the pilot.

The pilot of ``bench_montecarlo.py --overcast`` (issue 21's layer of optical depth 15, Mie droplets r_e 10 um at
1000-1500 m, Earth air, sun zenith 60 deg, 11 wavelengths 360-760 nm, 20 of the 200 equal-area views, one thread).

* ``--ab SETTING [SETTING ...]``: the pilot once per setting, in turn, ``--rounds`` times (seed 1 + round), in this
  process. A setting is ``NAME=VALUE[,NAME=VALUE]`` of ``skyscatter.montecarlo.driver`` attributes (``-``: the
  defaults). Printed per run: paths per CPU-second, scattering events per path, the per-path relative standard
  deviation (median over the 220 outputs, and per wavelength), the efficiency ``1 / (variance x CPU time per
  path)`` and the minutes a 1 % median standard error would take on 2 cores (scaled from the pilot, not run);
  per round the z-scores of each setting's radiances against the first's (``(b - a) / hypot(se_a, se_b)``: mean
  about 0 and spread about 1 for independent unbiased estimates, less where they share random numbers).
* ``--spectral``: the cost of the hero-wavelength MIS. The pilot with the droplets' phase function (and its
  forward peak), the cloud's extinction, the air's coefficients or all three made the same at every wavelength
  (those of 560 nm) by patching ``driver.prepare_medium``; the per-wavelength per-path standard deviations show
  which spectral difference the shared paths pay for. Then, from the phase tables, the per-vertex second moment
  ``m_i = int P_i^2 / q dOmega`` of sampling every vertex's direction from the group's mixture ``q = mean_j P_j``
  instead of the hero's (a path of ``n`` vertices pays about ``m_i^n``).

Usage: ``python benchmarks/montecarlo_overcast_variance.py --ab - SPLIT_FACTOR=1 [--samples 4096] [--rounds 2]``,
``python benchmarks/montecarlo_overcast_variance.py --spectral``. The track-length next-event estimates and the
exponential transform measured in docs/clouds.md (Speed) were driver options ``TRACK_NEE`` and ``STRETCH`` at
commit f83b904 (removed after): run this script from that commit's tree to repeat them.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import math
import os
import time

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters
from skyscatter.atmosphere.clouds import CloudLayer
from skyscatter.montecarlo import driver, sky_radiance
from skyscatter.montecarlo.dataset import equal_area_directions

WAVELENGTHS = np.arange(360.0, 761.0, 40.0)
SUN_ZENITH = math.radians(60.0)
REF = 5  # 560 nm, the wavelength whose optics the --spectral runs give every wavelength


def _job():
    atm = AtmosphereParameters(particles=(CloudLayer(1000.0, 1500.0, 15.0, effective_radius=10e-6),))
    return atm, equal_area_directions(200)[::10]


def _parse(setting: str) -> dict:
    if setting == "-":
        return {}
    out = {}
    for item in setting.split(","):
        name, value = item.split("=", 1)
        if not hasattr(driver, name):
            raise SystemExit(f"driver has no attribute {name!r}")
        out[name] = ast.literal_eval(value)
    return out


def _run(atm, dirs, setting: dict, samples: int, seed: int):
    saved = {k: getattr(driver, k) for k in setting}
    try:
        for k, v in setting.items():
            setattr(driver, k, v)
        c0 = time.process_time()
        r = sky_radiance(atm, dirs, WAVELENGTHS, sun_zenith=SUN_ZENITH, samples=samples, scheduler="synchronous",
                         seed=seed)
        return r, time.process_time() - c0
    finally:
        for k, v in saved.items():
            setattr(driver, k, v)


def _report(label: str, r, cpu: float, n_dirs: int) -> None:
    rate = n_dirs * r.samples / cpu
    sdv = r.relative_stderr * math.sqrt(r.samples)
    sd = float(np.median(sdv))
    print(f"{label}: {rate:,.0f} paths per CPU-second, {r.mean_vertices:.1f} events per path, per-path relative std "
          f"{sd:.3f} (per wavelength {' '.join(f'{x:.2f}' for x in np.median(sdv, axis=0))}), efficiency "
          f"{rate / sd**2:,.0f}, 1 % median standard error {200 * (sd / 0.01) ** 2 / rate / 120:.1f} min on 2 cores "
          f"(load {os.getloadavg()[0]:.1f})", flush=True)


def ab(settings: list[str], samples: int, rounds: int) -> None:
    atm, dirs = _job()
    parsed = [_parse(s) for s in settings]
    for s in parsed:
        _run(atm, dirs[:1], s, 8, 99)  # compile
    print(f"load average {os.getloadavg()[0]:.1f} at start; {dirs.shape[0]} views x {samples} paths", flush=True)
    for k in range(rounds):
        res = []
        for label, s in zip(settings, parsed, strict=True):
            r, cpu = _run(atm, dirs, s, samples, 1 + k)
            _report(f"round {k} {label}", r, cpu, dirs.shape[0])
            res.append(r)
        a = res[0]
        for label, b in zip(settings[1:], res[1:], strict=True):
            z = (b.radiance - a.radiance) / np.hypot(a.stderr, b.stderr)
            print(f"   round {k} z {label} - {settings[0]}: mean {z.mean():+.2f}, std {z.std():.2f}, largest |z| "
                  f"{np.abs(z).max():.2f} ({z.size} values)", flush=True)


def _grey(medium, what: str):
    """``medium`` with the optics ``what`` (phase, ext, air, all) of wavelength ``REF`` at every wavelength."""
    m = medium
    ch: dict = {}
    if what in ("phase", "all") and m.peak_lobe >= 0:
        tab = int(m.lobe_tab[m.peak_lobe])
        tval, tcdf = m.tval.copy(), m.tcdf.copy()
        tval[tab] = tval[tab, REF]
        tcdf[tab] = tcdf[tab, REF]
        ch.update(tval=tval, tcdf=tcdf)
        for name in ("pval", "pcdf", "pa", "dval", "dcdf"):
            v = getattr(m, name).copy()
            v[:] = v[REF]
            ch[name] = v
    coef, scat = m.coef.copy(), m.scat.copy()
    if what in ("ext", "all"):
        coef[:, 3:] = coef[REF, 3:]
        scat[:, 3:] = scat[REF, 3:]
    if what in ("air", "all"):
        coef[:, :3] = coef[REF, :3]
        scat[:, :3] = scat[REF, :3]
    return dataclasses.replace(m, coef=coef, scat=scat, **ch)


def spectral(samples: int) -> None:
    atm, dirs = _job()
    original = driver.prepare_medium
    for what in ("none", "phase", "ext", "air", "all"):
        driver.prepare_medium = original if what == "none" else (
            lambda *a, _w=what, **k: _grey(original(*a, **k), _w))
        try:
            _run(atm, dirs[:1], {}, 8, 99)
            r, cpu = _run(atm, dirs, {}, samples, 1)
        finally:
            driver.prepare_medium = original
        _report(f"optics of {WAVELENGTHS[REF]:.0f} nm at every wavelength: {what}", r, cpu, dirs.shape[0])
    m = original(atm, WAVELENGTHS)
    tab = int(m.lobe_tab[m.peak_lobe])
    x = np.unique(np.concatenate([m.tmu, np.linspace(-1.0, 1.0, 20001), 1.0 - np.logspace(-9.0, 0.0, 40001)]))
    p = np.array([np.interp(x, m.tmu, m.tval[tab, i]) for i in range(WAVELENGTHS.size)])  # linear in mu: exact
    q = p.mean(axis=0)
    moments = [float(np.trapezoid(p[i] ** 2 / q, x) * 2.0 * math.pi) for i in range(WAVELENGTHS.size)]
    print("per-vertex second moment of sampling the group's mixture instead of the hero's phase function: "
          + ", ".join(f"{w:.0f}: {v:.4f} (^35 {v**35:.1f})" for w, v in zip(WAVELENGTHS, moments, strict=True)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ab", nargs="+", metavar="SETTING")
    ap.add_argument("--spectral", action="store_true")
    ap.add_argument("--samples", type=int, default=None, help="paths per view (4096 for --ab, 1024 --spectral)")
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    if args.ab:
        ab(args.ab, args.samples or 4096, args.rounds)
    if args.spectral:
        spectral(args.samples or 1024)
    if not (args.ab or args.spectral):
        ap.print_help()


if __name__ == "__main__":
    main()
