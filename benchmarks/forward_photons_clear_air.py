"""Clear air, 550 nm: the forward photons' ground diffuse irradiance against backward paths and the tables.

``montecarlo.domain.domain_quantities`` (``T - T_direct`` at the base of an empty periodic field) against
``montecarlo.domain.ground_irradiance`` (backward cosine-distributed paths), the precomputed tables
(``PrecomputedAtmosphere.ground_irradiance``, rgb, the 550 nm table; ``--tables``: cached or computed once) and,
with ``--radius-scale 1000`` (the plane-parallel limit), DISORT (disortpp, 32 streams, 150 layers). Figures:
docs/clouds.md (Forward photons for fluxes).

``nice python benchmarks/forward_photons_clear_air.py --photons 1000000 --paths 400000 --tables --seed 2``
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
from skyscatter.atmosphere.particles import AnalyticParticles
from skyscatter.montecarlo.domain import domain_quantities, ground_irradiance

ap = argparse.ArgumentParser()
ap.add_argument("--photons", type=int, default=20000)
ap.add_argument("--paths", type=int, default=20000)
ap.add_argument("--elevs", default="30,10")
ap.add_argument("--tables", action="store_true")
ap.add_argument("--radius-scale", type=float, default=1.0,
                help="planet radius in Earth radii (the air unchanged); >= 100 adds DISORT (plane-parallel)")
ap.add_argument("--seed", type=int, default=11)
a = ap.parse_args()
atm = AtmosphereParameters()
plane = a.radius_scale >= 100.0
if a.radius_scale != 1.0:
    rb = atm.bottom_radius * a.radius_scale
    atm = AtmosphereParameters(bottom_radius=rb, top_radius=rb + atm.thickness)
wl = [550.0]
hg = AnalyticParticles("marker", DensityProfile.uniform(), 1.0, 1.0, "henyey-greenstein", 0.85)
empty = CloudField(np.zeros((1, 1, 1)), 1000.0, 0.0, 100.0, hg, origin=(0.0, 0.0))
print("load", os.getloadavg(), "albedo", atm.ground_albedo_at(wl), "thickness", atm.thickness)
if a.tables:
    from skyscatter.precomputed import cached_atmosphere
    tab = cached_atmosphere(atm, tables="rgb", progress=False)
for elev in [float(e) for e in a.elevs.split(",")]:
    sz = math.radians(90 - elev)
    e0 = float(atm.solar_irradiance_at(wl)[0]) * math.cos(sz)
    t0 = time.perf_counter()
    d = domain_quantities(atm, empty, wl, sun_zenith=sz, up_views=None, samples=a.photons, seed=a.seed)
    t1 = time.perf_counter()
    fwd = d.transmittance[0, 0, 0] - d.direct_transmittance[0, 0, 0]
    fe = d.transmittance_stderr[0, 0, 0]
    line = (f"elev {elev:4.0f}: diffuse T (/mu0F0) forward {fwd:.5f} +- {fe:.5f} [{t1-t0:.1f} s]"
            f"  direct {d.direct_transmittance[0,0,0]:.4f}")
    if a.paths:
        g = ground_irradiance(atm, wl, sun_zenith=sz, samples=a.paths, seed=a.seed + 1)
        t2 = time.perf_counter()
        bwd, be = g.diffuse[0, 0] / e0, g.diffuse_stderr[0, 0] / e0
        z = (fwd - bwd) / math.hypot(fe, be)
        line += f"  backward {bwd:.5f} +- {be:.5f} [{t2-t1:.1f} s]  fwd/bwd-1 {fwd/bwd-1:+.2%} ({z:+.1f} sigma)"
    print(line)
    if a.tables:
        sun = np.array([0.0, math.sin(sz), math.cos(sz)])
        es, ek = tab.ground_irradiance(np.array([0, 0, atm.bottom_radius + 0.01]), np.array([0, 0, 1.0]), sun)
        i = int(np.argmin(abs(tab.wavelengths - 550)))
        tk = ek[i] / (float(atm.solar_irradiance_at([tab.wavelengths[i]])[0]) * math.cos(sz))
        print(f"      tables ({tab.wavelengths[i]:.0f} nm) diffuse {tk:.5f}: fwd/tables-1 {fwd/tk-1:+.2%}"
              + (f"  bwd/tables-1 {bwd/tk-1:+.2%}" if a.paths else ""))
    if plane:
        sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
        import disortpp

        from disort_reference import _layer_integral, cornette_shanks_moments
        n_layers, nm = 150, 400
        edges = np.linspace(atm.thickness, 0.0, n_layers + 1)
        z_hi, z_lo = edges[:-1], edges[1:]
        br = float(atm.rayleigh_scattering_at(wl)[0])
        bme = float(atm.mie_extinction_at(wl)[0])
        bms = float(atm.mie_scattering_at(wl)[0])
        bo = float(atm.ozone_absorption_at(wl)[0])
        tr = br * _layer_integral(atm.rayleigh_density, z_lo, z_hi)
        im = _layer_integral(atm.aerosol_component.density, z_lo, z_hi)
        tau = tr + bme * im + bo * _layer_integral(atm.ozone_density, z_lo, z_hi)
        ssa = (tr + bms * im) / tau
        an = atm.aerosol_component.analytic_phase
        chi_m = cornette_shanks_moments(an.g, nm) if an is not None and an.kind == "cornette-shanks" else \
            atm.aerosol_phase_table(wl).legendre_moments(nm + 1)[0]
        chi_r = np.zeros(nm + 1)
        chi_r[0], chi_r[2] = 1.0, 0.1
        fr = tr / (tr + bms * im)
        mom = fr[:, None] * chi_r + (1 - fr)[:, None] * chi_m
        cfg = disortpp.DisortConfig(tau.size, 32, nm)
        cfg.flags.use_lambertian_surface = True
        cfg.flags.use_user_tau = True
        cfg.flags.comp_only_fluxes = True
        cfg.num_user_tau = 1
        cfg.allocate()
        cfg.delta_tau = [float(t) for t in tau]
        cfg.single_scat_albedo = [float(s) for s in ssa]
        cfg.phase_function_moments = [[float(c) for c in row] for row in mom]
        cfg.tau_user = [float(tau.sum())]
        cfg.bc.direct_beam_flux = 1.0
        cfg.bc.direct_beam_mu = math.cos(sz)
        cfg.bc.direct_beam_phi = 0.0
        cfg.bc.surface_albedo = float(np.mean(atm.ground_albedo_at(wl)))
        res = disortpp.DisortSolver().solve(cfg)
        dd = res.flux_down[0] / math.cos(sz)
        ddir = res.flux_direct_beam[0] / math.cos(sz)
        print(f"      DISORT (plane-parallel, 32 streams) diffuse {dd:.5f} direct {ddir:.4f}:"
              f" fwd/DISORT-1 {fwd/dd-1:+.2%}" + (f"  bwd/DISORT-1 {bwd/dd-1:+.2%}" if a.paths else ""))
