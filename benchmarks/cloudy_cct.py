"""The cloudy sky's correlated colour temperature (CCT) of the diffuse light on the ground against the Monte Carlo,
with the Monte Carlo's CCT uncertainty (docs/clouds.md, "Accuracy against the Monte Carlo").

Per case (cloud optical depth 1, 5, 15, 30, 60; sun 60, 30, 10, 2 deg; water cloud 1000-1500 m, r_e 10 um, Earth
air, ground albedo 0.2): the Monte Carlo references pooled over their independent runs
(``tests/cloudy_cct_reference.py``: the stored ``cloudy_montecarlo.json`` with ``cloudy_sun30_forward.json`` at
sun 30 deg and ``cloudy_low_sun.json`` at 10 and 2 deg), the model's diffuse irradiance against them, the CCT of
the model and of the Monte Carlo (the model's spectrum times the ratio interpolated between 450 / 550 / 650 nm,
Hernandez 1999) with the latter's standard error (the three ratios drawn within their standard errors), and the
CCT against the stored single run alone (the table of 2026-12-03). A Markdown table for docs/clouds.md.

``--aliased-optics``: the model with the droplets' Mie optics on the size quadrature of before 2026-12-03 (24
nodes per e, which aliased the phase function's ripple; docs/clouds.md "Radiance under clouds"), with which the
stored references of 2026-12-02 were traced: what that change alone does to the model's irradiance and CCT.

``PYTHONPATH=src python benchmarks/cloudy_cct.py [--taus 1,5,15,30,60] [--suns 60,30,10,2] [--draws 4000]
[--aliased-optics]``
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

from skyscatter.sky.cloudy import CloudySky

sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
import cloudy_cct_reference as ref_mod  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--taus", default="1,5,15,30,60")
    ap.add_argument("--suns", default="60,30,10,2")
    ap.add_argument("--draws", type=int, default=4000)
    ap.add_argument("--aliased-optics", action="store_true", help="the droplets' optics at 24 nodes per e")
    a = ap.parse_args()
    if a.aliased_optics:
        from skyscatter.atmosphere import mie_optics
        from skyscatter.atmosphere.size_distributions import NODES_PER_E

        resolved = mie_optics.water_droplets
        mie_optics.water_droplets = lambda r, v, wl, angles=None, nodes_per_e=None: resolved(  # type: ignore
            r, v, wl, angles, NODES_PER_E if nodes_per_e is None else nodes_per_e)
    print("| optical depth | sun | reference (runs, photons or paths) | diffuse E, model vs MC (450 / 550 / 650 nm) "
          "| MC standard error | CCT model / MC +- sigma | model - MC | stored run alone: MC CCT +- sigma | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for sun in (float(s) for s in a.suns.split(",")):
        for tau in (float(t) for t in a.taus.split(",")):
            t0 = time.process_time()
            mc_data = ref_mod.MONTECARLO
            sky = CloudySky(math.radians(90.0 - sun), 0.0, cloud_optical_depth=tau,
                            cloud_base=mc_data["cloud_base_m"], cloud_top=mc_data["cloud_top_m"],
                            ground_albedo=mc_data["ground_albedo"])
            model = sky.diffuse_fluxes(ref_mod.WAVELENGTHS)[0]
            spectrum = sky.diffuse_fluxes(ref_mod.FINE)[0]
            dt = time.process_time() - t0
            runs, kind = ref_mod.reference_runs(tau, sun)
            ref = ref_mod.reference(tau, sun)
            first = ref_mod.pooled(runs[:1])
            _, t_first, s_first = ref_mod.monte_carlo_cct(spectrum, model, first[0], first[1], a.draws)
            if ref is None:
                print(f"| {tau:g} | {sun:g} | {kind}, {first[2]} (too few) | | | | | ({t_first:.0f} +- {s_first:.0f} K)"
                      f" | {dt:.1f} |", flush=True)
                continue
            mc, err, n, kind = ref
            t_model, t_mc, s_mc = ref_mod.monte_carlo_cct(spectrum, model, mc, err, a.draws)
            d = " / ".join(f"{100 * v:+.1f}" for v in model / mc - 1.0)
            e = " / ".join(f"{100 * v:.1f}" for v in err / mc)
            print(f"| {tau:g} | {sun:g} | {kind}, {len(runs)} runs, {n} | {d} % | {e} % | {t_model:.0f} / {t_mc:.0f} "
                  f"+- {s_mc:.0f} K | {t_model - t_mc:+.0f} K ({(t_model - t_mc) / s_mc:+.1f} sigma) "
                  f"| {t_first:.0f} +- {s_first:.0f} K | {dt:.1f} |", flush=True)
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
