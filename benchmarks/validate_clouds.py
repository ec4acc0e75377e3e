"""Long validations of the Monte Carlo through clouds (the figures of docs/clouds.md; small versions are tests).

Sections (``python benchmarks/validate_clouds.py SECTION [--scale S]``; ``all`` runs them in turn):

* ``i3rc`` - I3RC Phase 1 case 1, experiments 1 and 2 ([Cahalan2005]; tests/data/i3rc_case1_consensus.csv):
  domain means and per-column R, T, nadir / 60-degree reflectivities and zenith transmissivity against the
  consensus, with the largest deviations and z-scores.
* ``disort5`` - DISORT test problem 5 (cloud C.1, optical depth 64, mu0 = 1): albedo, diffuse transmittance
  (omega = 1) and the fluxes at optical depths 3.2, 12.8 and 48 (omega = 0.9), shells and field.
* ``waterclouds`` - plane-parallel water clouds (Mie droplets r_e = 10 um, v_e = 0.1, 550 nm; optical depth 5,
  15, 30; sun zenith 0, 30, 60 deg; alone or over a Rayleigh atmosphere; ground albedo 0 and 0.6) against
  DISORT (disortpp, 64 streams, the Legendre moments of the same phase table, delta-M and the intensity correction with
  the table itself (tests/disort_reference.py; before 2026-12-02 none was applied), 100 layers): diffuse ground
  irradiance and radiance 10 deg or more above the horizon.
* ``waterclouds-irradiance`` - the ground diffuse irradiance of ``waterclouds`` alone, 12 of its cases (minutes).
* ``waterclouds-radiance`` - the radiance of ``waterclouds`` alone, the same 12 cases (``--cases rest``: the other
  24; ``all``: the 36), 6 views each (zenith 0, 60, 80 deg; azimuth 90 and 180 deg from the sun; those 25 deg or
  more from the sun compared): per view the relative difference and z-score, per case the largest, and the mean
  relative difference over all views.
* ``overcast`` - the luminance gradation under a thick stratus (optical depth 30, base 500 m, top 1000 m,
  Earth air, ground albedo 0.2) against the CIE overcast sky (1 + 2 sin h) / 3, and the correlated colour
  temperature of the diffuse light at sun elevations 60, 30, 10 deg.
* ``overcast-cct`` - the colour temperatures of ``overcast`` alone (forward photons: a minute, not an hour).

``--scale`` multiplies the paths (default 1). Prints a report; machine and load average stated.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from skyscatter.atmosphere import AtmosphereParameters, DensityProfile
from skyscatter.atmosphere.clouds import CloudField
from skyscatter.atmosphere.particles import AnalyticParticles, TabulatedParticles
from skyscatter.atmosphere.phase_table import PhaseTable
from skyscatter.atmosphere.spectra import PowerLawSpectrum
from skyscatter.montecarlo import sky_radiance
from skyscatter.montecarlo.domain import domain_quantities, ground_irradiance  # noqa: F401

DATA = Path(__file__).parents[1] / "tests" / "data"
RB = 6.36e9


def cloud_only(thickness=2000.0, albedo=0.0, **kw):
    return AtmosphereParameters(bottom_radius=RB, top_radius=RB + thickness, rayleigh_scattering=0.0,
                                mie_angstrom_beta=0.0, ozone_column=0.0, ground_albedo=albedo,
                                sun_angular_radius=1e-6, **kw)


def i3rc(scale):
    import pandas as pd

    cons = pd.read_csv(DATA / "i3rc_case1_consensus.csv", comment="#")
    hg = AnalyticParticles("step cloud", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)
    field = CloudField.i3rc_step_cloud(hg)
    n = int(16384 * scale)
    for exp in (1, 2):
        t0 = time.perf_counter()
        if exp == 1:
            r = domain_quantities(cloud_only(), field, [550.0], sun_zenith=0.0,
                                  up_views=[(0.0, 0.0), (math.radians(60), math.radians(270))], samples=n, seed=11)
            quantities = {"R": (r.reflectance, r.reflectance_stderr), "T": (r.transmittance, r.transmittance_stderr),
                          "Iu": (r.up_reflectivity[0], r.up_reflectivity_stderr[0]),
                          "I602": (r.up_reflectivity[1], r.up_reflectivity_stderr[1])}
            t_ref = cons["exp1_T"].mean()
        else:
            r = domain_quantities(cloud_only(), field, [550.0], sun_zenith=math.radians(60),
                                  sun_azimuth=math.radians(270),
                                  up_views=[(0.0, 0.0), (math.radians(60), math.radians(270))],
                                  down_views=[(0.0, 0.0)], samples=n, seed=12)
            quantities = {"R": (r.reflectance, r.reflectance_stderr),
                          "Iu": (r.up_reflectivity[0], r.up_reflectivity_stderr[0]),
                          "I602": (r.up_reflectivity[1], r.up_reflectivity_stderr[1]),
                          "Id": (r.down_reflectivity[0], r.down_reflectivity_stderr[0])}
            t_ref = 1.0 - cons["exp2_R"].mean()
        re_, te_ = r.mean_stderr
        r_ref = cons[f"exp{exp}_R"].mean()
        print(f"I3RC exp {exp}: {n} paths per column and view, {r.photons} photons, {time.perf_counter() - t0:.0f} s")
        print(f"  domain R {r.mean_reflectance[0]:.5f} +- {re_[0]:.5f} (consensus {r_ref:.5f}, "
              f"{r.mean_reflectance[0] / r_ref - 1:+.2%}); T {r.mean_transmittance[0]:.5f} +- {te_[0]:.5f} "
              f"(consensus {t_ref:.5f}, {r.mean_transmittance[0] / t_ref - 1:+.2%})")
        for name, (v, e) in quantities.items():
            mc, err = v[:, 0, 0], e[:, 0, 0]
            ref = cons[f"exp{exp}_{name}"].to_numpy()
            rel = mc / ref - 1
            z = (mc - ref) / err
            print(f"  {name:5s} per column: median |rel| {np.median(np.abs(rel)):.2%}, max |rel| "
                  f"{np.max(np.abs(rel)):.2%} (column {np.argmax(np.abs(rel)) + 1}), median |z| "
                  f"{np.median(np.abs(z)):.2f}, max |z| {np.max(np.abs(z)):.1f}, median rel stderr "
                  f"{np.median(err / mc):.2%}; within 3 sigma + 1 %: "
                  f"{np.mean(np.abs(mc - ref) < 3 * err + 0.01 * ref):.0%}")


def c1_table():
    import pandas as pd

    beta = pd.read_csv(DATA / "disort_cloud_c1_moments.csv", comment="#")["beta"].to_numpy()
    return PhaseTable.from_legendre_moments(beta / (2 * np.arange(beta.size) + 1), [550.0], clip_negative=True)


def disort5(scale):
    table = c1_table()
    n = int(200_000 * scale)
    ref = {1.0: {"albedo": 2.66174 / math.pi, "diffuse T": 0.479851 / math.pi},
           0.9: {3.2: (1.74767, 0.270485), 12.8: (0.233975, 0.0374252), 48.0: (6.38345e-05, 1.02904e-05)}}
    for omega in (1.0, 0.9):
        ssa = PowerLawSpectrum(omega, 1000.0, 0.0, "albedo")
        for as_field in (False, True):
            if as_field:
                drops = TabulatedParticles("C.1", DensityProfile.uniform(), PowerLawSpectrum(1.0, 1000.0, 0.0, "e"),
                                           ssa, table)
                atm, field = cloud_only(), CloudField(np.full((1, 1, 1), 0.064), 1000.0, 0.0, 1000.0, drops,
                                                      origin=(0.0, 0.0))
            else:
                slab = TabulatedParticles("C.1", DensityProfile.box(0.0, 1000.0),
                                          PowerLawSpectrum(0.064, 1000.0, 0.0, "e"), ssa, table)
                atm = cloud_only(particles=(slab,))
                hg = AnalyticParticles("x", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)
                field = CloudField(np.zeros((1, 1, 1)), 1000.0, 0.0, 1000.0, hg, origin=(0.0, 0.0))
            t0 = time.perf_counter()
            levels = [1000.0 - t / 0.064 for t in (3.2, 12.8, 48.0)] if omega < 1 else None
            r = domain_quantities(atm, field, [550.0], sun_zenith=0.0, up_views=None, samples=n, seed=21,
                                  levels=levels)
            how = "field" if as_field else "shells"
            head = f"DISORT 5, omega {omega:g}, {how}, {r.photons} photons ({time.perf_counter() - t0:.0f} s):"
            if omega == 1.0:
                re_, te_ = r.mean_stderr
                a = r.mean_reflectance[0]
                td = r.mean_transmittance[0] - r.direct_transmittance.mean()
                print(f"{head} albedo {a:.5f} +- {re_[0]:.5f} ({a / ref[1.0]['albedo'] - 1:+.2%}), diffuse T "
                      f"{td:.5f} +- {te_[0]:.5f} ({td / ref[1.0]['diffuse T'] - 1:+.2%})")
            else:
                print(head)
                for tau, (dn, up) in ref[0.9].items():
                    j = int(np.flatnonzero(np.isclose(r.levels, 1000.0 - tau / 0.064))[0])
                    d_mc = r.level_down[j].mean() - r.level_direct[j].mean()
                    u_mc = r.level_up[j].mean()
                    print(f"  tau {tau:4.1f}: diffuse down {d_mc * math.pi:.5e} +- "
                          f"{r.level_down_stderr[j].mean() * math.pi:.1e} ({d_mc * math.pi / dn - 1:+.2%}), up "
                          f"{u_mc * math.pi:.5e} +- {r.level_up_stderr[j].mean() * math.pi:.1e} "
                          f"({u_mc * math.pi / up - 1:+.2%})")


def _disort_cloud(*args, **kw):
    sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
    from disort_reference import disort_cloud

    return disort_cloud(*args, **kw)


def _case(tau, air, albedo):
    """(layer, atmosphere) of a water-cloud case, ``air`` "alone" or "rayleigh" (tests/disort_reference.py)."""
    sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
    from disort_reference import water_cloud_case

    return water_cloud_case(tau, air == "rayleigh", albedo, RB)


def waterclouds(scale):
    wl = 550.0
    n = int(40_000 * scale)
    view_zen = np.radians([0.0, 30.0, 60.0, 80.0])
    view_azi = np.radians([0.0, 90.0, 180.0])
    hg = AnalyticParticles("x", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)
    empty = CloudField(np.zeros((1, 1, 1)), 1000.0, 0.0, 1000.0, hg, origin=(0.0, 0.0))
    rows = []
    for tau in (5.0, 15.0, 30.0):
        for air in ("alone", "rayleigh"):
            for albedo in (0.0, 0.6):
                layer, atm = _case(tau, air, albedo)
                for sun in (0.0, 30.0, 60.0):
                    sz = math.radians(sun)
                    t0 = time.perf_counter()
                    dirs = np.array([[math.sin(z) * math.sin(a), math.sin(z) * math.cos(a), math.cos(z)]
                                     for z in view_zen for a in view_azi])
                    mc = sky_radiance(atm, dirs, [wl], sun_zenith=sz, samples=n, seed=31)
                    # the diffuse ground irradiance by forward photons (an empty field marks the domain)
                    d = domain_quantities(atm, empty, [wl], sun_zenith=sz, up_views=None, samples=4 * n, seed=32)
                    e0 = float(atm.solar_irradiance_at([wl])[0])
                    rad_ref, dif_ref = _disort_cloud(atm, layer, wl, sz, view_zen, view_azi, albedo)
                    rad_mc = mc.radiance[:, 0].reshape(view_zen.size, view_azi.size) / e0
                    err = mc.stderr[:, 0].reshape(view_zen.size, view_azi.size) / e0
                    dif_mc = d.transmittance[0, 0, 0] - d.direct_transmittance[0, 0, 0]
                    dif_err = d.transmittance_stderr[0, 0, 0]
                    # radiances 10 deg or more above the horizon and 25 deg or more from the sun (the aureole
                    # inside the diffraction peak needs the solar disc DISORT does not have)
                    cosang = (np.cos(view_zen)[:, None] * math.cos(sz)
                              + np.sin(view_zen)[:, None] * math.sin(sz) * np.cos(view_azi)[None, :])
                    keep = cosang < math.cos(math.radians(25.0))
                    rel = np.where(keep, rad_mc / rad_ref - 1, 0.0)
                    rows.append((tau, air, albedo, sun, dif_mc / dif_ref - 1, dif_err / dif_ref,
                                 np.max(np.abs(rel)), np.median(err / rad_mc)))
                    print(f"tau {tau:4.1f} {air:8s} A {albedo:.1f} sun {sun:4.1f}: diffuse E {dif_mc:.4f} +- "
                          f"{dif_err:.4f} vs DISORT {dif_ref:.4f} ({dif_mc / dif_ref - 1:+.2%}); radiance max |rel| "
                          f"{np.max(np.abs(rel)):.2%}, max |z| "
                          f"{np.max(np.where(keep, np.abs(rad_mc - rad_ref) / err, 0)):.1f}, "
                          f"median rel stderr {np.median(err / rad_mc):.2%} ({time.perf_counter() - t0:.0f} s)",
                          flush=True)
    r = np.array([row[4:] for row in rows], dtype=float)
    print(f"waterclouds: {len(rows)} cases; diffuse irradiance median |rel| {np.median(np.abs(r[:, 0])):.2%}, max "
          f"{np.max(np.abs(r[:, 0])):.2%}; radiance max |rel| median {np.median(r[:, 2]):.2%}, max "
          f"{np.max(r[:, 2]):.2%}")


#: 12 of the 36 water-cloud cases (optical depth, air, ground albedo, sun zenith [deg]): each optical depth, sun, air
#: and albedo appears at least four times
IRRADIANCE_CASES = ((5, "alone", 0.0, 0), (15, "alone", 0.0, 30), (30, "alone", 0.0, 60), (5, "rayleigh", 0.6, 30),
                    (15, "rayleigh", 0.6, 60), (30, "rayleigh", 0.6, 0), (5, "rayleigh", 0.0, 60),
                    (15, "rayleigh", 0.0, 0), (30, "rayleigh", 0.0, 30), (5, "alone", 0.6, 60),
                    (15, "alone", 0.6, 0), (30, "alone", 0.6, 30))
#: All 36 water-cloud cases, in the same order as ``waterclouds``.
ALL_CASES = tuple((tau, air, albedo, sun) for tau in (5, 15, 30) for air in ("alone", "rayleigh")
                  for albedo in (0.0, 0.6) for sun in (0, 30, 60))
#: The 24 cases not in IRRADIANCE_CASES.
REST_CASES = tuple(c for c in ALL_CASES if c not in IRRADIANCE_CASES)
CASE_SETS = {"first12": IRRADIANCE_CASES, "rest": REST_CASES, "all": ALL_CASES}


def waterclouds_irradiance(scale, cases=IRRADIANCE_CASES):
    """The ground diffuse irradiance of ``waterclouds`` alone (forward photons, 20000 x scale per case; no
    radiances: seconds per case) for ``cases`` (default IRRADIANCE_CASES)."""
    wl = 550.0
    n = int(20_000 * scale)
    hg = AnalyticParticles("x", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)
    empty = CloudField(np.zeros((1, 1, 1)), 1000.0, 0.0, 1000.0, hg, origin=(0.0, 0.0))
    rel = []
    for tau, air, albedo, sun in cases:
        layer, atm = _case(tau, air, albedo)
        sz = math.radians(sun)
        t0 = time.perf_counter()
        d = domain_quantities(atm, empty, [wl], sun_zenith=sz, up_views=None, samples=n, seed=32)
        _, dif_ref = _disort_cloud(atm, layer, wl, sz, np.radians([0.0]), np.radians([0.0]), albedo)
        dif_mc = d.transmittance[0, 0, 0] - d.direct_transmittance[0, 0, 0]
        err = d.transmittance_stderr[0, 0, 0]
        rel.append(dif_mc / dif_ref - 1)
        print(f"tau {tau:4.1f} {air:8s} A {albedo:.1f} sun {sun:4.1f}: diffuse T {dif_mc:.5f} +- {err:.5f} vs DISORT "
              f"{dif_ref:.5f}: {rel[-1]:+.2%} (stderr {err / dif_ref:.2%}; {time.perf_counter() - t0:.0f} s)",
              flush=True)
    print(f"waterclouds-irradiance: {len(rel)} cases, median |rel| {np.median(np.abs(rel)):.2%}, max "
          f"{np.max(np.abs(rel)):.2%}")


def waterclouds_radiance(scale, cases=IRRADIANCE_CASES):
    """The radiance of ``waterclouds`` for ``cases`` (default IRRADIANCE_CASES; 16384 x scale paths per view)."""
    wl = 550.0
    n = int(16384 * scale)
    vz = np.radians([0.0, 60.0, 80.0])
    va = np.radians([90.0, 180.0])
    dirs = np.array([[math.sin(z) * math.sin(a), math.sin(z) * math.cos(a), math.cos(z)] for z in vz for a in va])
    rels, zs, bad = [], [], 0
    for tau, air, albedo, sun in cases:
        layer, atm = _case(tau, air, albedo)
        sz = math.radians(sun)
        t0 = time.perf_counter()
        mc = sky_radiance(atm, dirs, [wl], sun_zenith=sz, samples=n, seed=61)
        rad_ref, _ = _disort_cloud(atm, layer, wl, sz, vz, va, albedo)
        e0 = float(atm.solar_irradiance_at([wl])[0])
        rad, err, ref = mc.radiance[:, 0] / e0, mc.stderr[:, 0] / e0, rad_ref.ravel()
        keep = dirs @ np.array([0.0, math.sin(sz), math.cos(sz)]) < math.cos(math.radians(25.0))
        rel = rad[keep] / ref[keep] - 1
        z = (rad[keep] - ref[keep]) / err[keep]
        rels.extend(rel)
        zs.extend(z)
        bad += int(np.sum(np.abs(rad[keep] - ref[keep]) > 0.02 * ref[keep] + 3 * err[keep]))
        print(f"tau {tau:4.1f} {air:8s} A {albedo:.1f} sun {sun:4.1f}: rel {', '.join(f'{v:+.2%}' for v in rel)}; "
              f"z {', '.join(f'{v:+.1f}' for v in z)}; median rel stderr {np.median(err[keep] / rad[keep]):.2%}; "
              f"{mc.mean_vertices:.1f} events per path ({time.perf_counter() - t0:.0f} s)", flush=True)
    rels, zs = np.array(rels), np.array(zs)
    print(f"waterclouds-radiance: {rels.size} views in {len(cases)} cases, {n} paths each; mean rel "
          f"{rels.mean():+.2%} +- {rels.std(ddof=1) / math.sqrt(rels.size):.2%}, max |rel| {np.max(np.abs(rels)):.2%}, "
          f"max |z| {np.max(np.abs(zs)):.1f}; views off by more than 2 % + 3 standard errors: {bad}")


def overcast(scale):
    from skyscatter.sky.montecarlo import MonteCarloSky

    wl = np.arange(380.0, 781.0, 25.0)
    n = int(8192 * scale)
    elev = np.radians([5.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0])
    atm = AtmosphereParameters(ground_albedo=0.2)
    for sun_elev in (60.0, 30.0, 10.0):
        t0 = time.perf_counter()
        sky = MonteCarloSky(math.radians(90.0 - sun_elev), atmosphere=atm, cloud_optical_depth=30.0, cloud_base=500.0,
                            cloud_top=1000.0, samples=n, seed=41)
        # azimuths 0, 90, 180, 270 deg at each elevation: the overcast is nearly uniform in azimuth
        az = np.radians([0.0, 90.0, 180.0, 270.0])
        dirs = np.array([[math.cos(h) * math.sin(a), math.cos(h) * math.cos(a), math.sin(h)]
                         for h in elev for a in az])
        L, err = sky.radiance_and_error(dirs, wl)
        from skyscatter.spectral import spectrum_to_xyz

        xyz = spectrum_to_xyz(L, wl)
        Y = xyz[:, 1].reshape(elev.size, az.size).mean(axis=1)
        grad = Y / Y[-1]
        cie = (1 + 2 * np.sin(elev)) / 3
        cct = diffuse_cct(atm, sky.cloud_layer, wl, sun_elev, 4 * n, seed=42)
        print(f"overcast tau 30, sun {sun_elev:.0f} deg ({time.perf_counter() - t0:.0f} s): L/L_zenith at h = "
              f"{', '.join(f'{math.degrees(h):.0f}:{v:.3f}' for h, v in zip(elev, grad, strict=True))}; CIE "
              f"{', '.join(f'{v:.3f}' for v in cie)}; max |MC/CIE - 1| {np.max(np.abs(grad / cie - 1)):.1%}; "
              f"diffuse global CCT {cct:.0f} K; median rel stderr {np.median(err / L):.2%}")


def diffuse_cct(atm, layer, wl, sun_elev, photons, seed):
    """Correlated colour temperature [K] of the diffuse light on the ground under ``layer`` (forward photons; an
    empty periodic field marks the domain; Hernandez 1999 through colour-science)."""
    import colour

    from skyscatter.spectral import spectrum_to_xyz, xyz_to_chromaticity

    hg = AnalyticParticles("x", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)
    empty = CloudField(np.zeros((1, 1, 1)), 1000.0, 0.0, 100.0, hg, origin=(0.0, 0.0))
    d = domain_quantities(atm.replace(particles=(layer,)), empty, wl, sun_zenith=math.radians(90 - sun_elev),
                          up_views=None, samples=photons, seed=seed)
    e0 = atm.solar_irradiance_at(wl) * math.sin(math.radians(sun_elev))
    diffuse = (d.transmittance[0, 0] - d.direct_transmittance[0, 0]) * e0
    xy = np.asarray(xyz_to_chromaticity(spectrum_to_xyz(diffuse, wl)))[:2]
    return float(np.squeeze(colour.temperature.xy_to_CCT(xy, method="Hernandez 1999")))


def overcast_cct(scale):
    """The colour part of ``overcast`` alone (forward photons only, no sky radiance: seconds, not the gradation's
    tens of minutes): CCT of the diffuse light at sun elevations 60, 30, 10 deg, two seeds each for the spread."""
    from skyscatter.sky.montecarlo import MonteCarloSky

    wl = np.arange(380.0, 781.0, 25.0)
    n = int(4 * 8192 * scale)
    atm = AtmosphereParameters(ground_albedo=0.2)
    for sun_elev in (60.0, 30.0, 10.0):
        t0 = time.perf_counter()
        layer = MonteCarloSky(math.radians(90.0 - sun_elev), atmosphere=atm, cloud_optical_depth=30.0,
                              cloud_base=500.0, cloud_top=1000.0).cloud_layer
        ccts = [diffuse_cct(atm, layer, wl, sun_elev, n, seed) for seed in (42, 43)]
        print(f"overcast tau 30, sun {sun_elev:.0f} deg: diffuse global CCT {ccts[0]:.0f} K (seed 42), "
              f"{ccts[1]:.0f} K (seed 43); {n} photons each ({time.perf_counter() - t0:.0f} s)", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("section", choices=["i3rc", "disort5", "waterclouds", "waterclouds-irradiance",
                                        "waterclouds-radiance", "overcast", "overcast-cct", "all"])
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--cases", choices=sorted(CASE_SETS), default="first12",
                    help="water-cloud cases of waterclouds-irradiance / -radiance: the first 12, the other 24, all 36")
    args = ap.parse_args()
    print(f"machine: {len(os.sched_getaffinity(0))} cores, load average {os.getloadavg()[0]:.1f} at start")
    for name in (["i3rc", "disort5", "waterclouds", "overcast"] if args.section == "all" else [args.section]):
        if name.startswith("waterclouds-"):
            globals()[name.replace("-", "_")](args.scale, CASE_SETS[args.cases])
        else:
            globals()[name.replace("-", "_")](args.scale)
    print(f"load average at the end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
